"""An exact rigid nominal for the three-axis laws' tests (tests/control, tests/testing): a
rest-to-rest rotation about a fixed body axis."""

from __future__ import annotations

import numpy as np


class EigenaxisSlew:
    """Rest-to-rest rotation by ``angle`` about a fixed body axis e in ``duration`` s, an exact
    rigid nominal for any inertia J (the three-axis TPBVP nominal of seed 003 stands in here).

    θ(τ) = Θ(35τ⁴ − 84τ⁵ + 70τ⁶ − 20τ⁷), τ = t/T: rate, acceleration and jerk vanish at both
    ends, so the torque starts and ends at zero as the paper's does (L827-L829). About a fixed
    axis the body and inertial components of e agree, so β = [cos θ/2, e sin θ/2], ω = θ̇ e and
    Euler's equation gives τ = J e θ̈ + ω × Jω (seed 003 Eq. 12).
    """

    def __init__(self, inertia, axis, angle, duration):
        self.inertia = np.asarray(inertia, float)
        self.axis = np.asarray(axis, float) / np.linalg.norm(axis)
        self.angle, self.duration = float(angle), float(duration)

    def _profile(self, t):
        s = np.clip(np.asarray(t, float) / self.duration, 0.0, 1.0)
        T, a = self.duration, self.angle
        return (
            a * (35 * s**4 - 84 * s**5 + 70 * s**6 - 20 * s**7),
            a * (140 * s**3 - 420 * s**4 + 420 * s**5 - 140 * s**6) / T,
            a * (420 * s**2 - 1680 * s**3 + 2100 * s**4 - 840 * s**5) / T**2,
        )

    def beta(self, t):
        theta = self._profile(t)[0][..., None]
        return np.concatenate([np.cos(theta / 2), np.sin(theta / 2) * self.axis], -1)

    def omega(self, t):
        return self._profile(t)[1][..., None] * self.axis

    def torque(self, t):
        _, rate, acc = self._profile(t)
        w = rate[..., None] * self.axis
        return acc[..., None] * (self.inertia @ self.axis) + np.cross(w, w @ self.inertia.T)
