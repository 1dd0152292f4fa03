r"""Star tracker as a sensor of a three-axis plant's ``attitude`` channel
(Junkins, Pollock & Rahman 1990 §2.3.4;
issue 14 part 4).

The measured attitude is the true one turned by a small body-axis error,

.. math::

    \beta_m = \delta\beta(\delta\theta) \otimes \beta, \qquad
    C(\beta_m) = e^{-[\delta\theta\times]}\,C(\beta), \qquad \delta\theta = L\,n,

with n the first three standard-normal columns of the channel's noise stream and
:math:`L L^T = P` the error covariance (rad², body axes): the convention of
:func:`flexsat.attitude.fit.rotation_error`.

This is the fast statistical model of the full pipeline (pinhole cameras, lost-in-space
identification, q-method): :meth:`StarTrackerSensor.from_tracker` runs
:func:`flexsat.attitude.star_tracker.monte_carlo` on seeded random attitudes and takes P as the
sample covariance of the errors of the accepted identifications (the per-frame QUEST covariance
agrees with it: tests/identify/test_star_tracker.py). A rejected identification is not modelled
(the default tracker identifies ≥ 99.9 % of frames; the rate is kept in
``identification_rate`` for the record): every sample gets a measurement.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from flexsat.dynamics.attitude import quaternion_exp, quaternion_multiply
from flexsat.dynamics.plant import Channel
from flexsat.input_checks import FieldError
from flexsat.sim.channels import ChannelSensor
from flexsat.units import FloatArray, QuantityArrayLike, to_si_array

if TYPE_CHECKING:
    from flexsat.attitude.star_tracker import StarTracker

__all__ = ["StarTrackerSensor"]


@dataclass(frozen=True)
class StarTrackerSensor(ChannelSensor):
    """Attitude measurement with a body-axis error of covariance ``covariance`` (module
    docstring); on the plant's ``attitude`` channel (unit Euler parameters, size 4).

    Parameters
    ----------
    covariance : array_like (3, 3) or (3,), str or Quantity
        Error covariance in rad² (a (3,) array: per-axis 1σ in rad, e.g. ``"1 arcsec"``
        strings accepted), symmetric positive semi-definite.
    identification_rate : float
        Fraction of frames identified by the full pipeline (recorded, not simulated).
    """

    covariance: QuantityArrayLike = 0.0
    identification_rate: float = 1.0
    # L with L Lᵀ = P, set by __post_init__
    _factor: FloatArray = field(
        init=False, repr=False, compare=False, default_factory=lambda: np.zeros((3, 3))
    )

    def __post_init__(self) -> None:
        super().__post_init__()
        try:
            given = np.asarray(self.covariance, float)
        except (TypeError, ValueError):  # a unit string or Quantity: per-axis sigmas
            given = None
        if given is not None and given.shape == (3, 3):
            cov = given
        else:
            sig = to_si_array(self.covariance, "rad", "covariance")
            if (
                sig.ndim > 1
                or sig.size not in (1, 3)
                or not np.all(np.isfinite(sig))
                or np.any(sig < 0)
            ):
                raise FieldError(
                    "covariance",
                    "give a (3, 3) matrix in rad² or per-axis sigmas "
                    f"(1 or 3 finite angles >= 0), got {self.covariance!r}",
                )
            cov = np.diag(np.broadcast_to(sig, (3,)) ** 2)
        if cov.shape != (3, 3) or not np.all(np.isfinite(cov)):
            raise FieldError(
                "covariance",
                "must be a finite (3, 3) matrix in rad² or 3 per-axis "
                f"sigmas, got shape {cov.shape}",
            )
        if np.max(np.abs(cov - cov.T)) > 1e-12 * max(np.max(np.abs(cov)), 1e-300):
            raise FieldError("covariance", "must be symmetric")
        vals, vecs = np.linalg.eigh(cov)
        if vals[0] < -1e-12 * max(vals[-1], 1e-300):
            raise FieldError(
                "covariance",
                f"must be positive semi-definite, smallest eigenvalue {vals[0]:.3g} rad²",
            )
        rate = float(self.identification_rate)
        if not 0 < rate <= 1:
            raise FieldError(
                "identification_rate", f"must lie in (0, 1], got {self.identification_rate!r}"
            )
        if self.derivative_of is not None:
            raise FieldError("derivative_of", "a star tracker measures the attitude itself")
        object.__setattr__(self, "covariance", cov)
        # L = V sqrt(Λ): L Lᵀ = P also when P is singular (where a Cholesky factor fails)
        object.__setattr__(self, "_factor", vecs * np.sqrt(np.clip(vals, 0, None)))
        # the engine draws noise for a sensor whose ``noise`` is non-zero: the largest 1σ
        object.__setattr__(self, "noise", float(np.sqrt(max(vals[-1], 0.0))))

    @classmethod
    def from_tracker(
        cls,
        tracker: StarTracker,
        n: int = 300,
        seed: int | np.random.Generator = 0,
        false_stars: int = 0,
        missing_fraction: float = 0.0,
    ) -> StarTrackerSensor:
        """Calibrated from the full pipeline (module docstring) on ``n`` random attitudes.

        Raises
        ------
        ValueError
            When fewer than 10 identifications are accepted (no covariance to estimate).
        """
        from flexsat.attitude.star_tracker import monte_carlo

        r = monte_carlo(tracker, n, seed, false_stars, missing_fraction)
        ok = r.errors[r.accepted]
        if ok.shape[0] < 10:
            raise FieldError(
                "tracker",
                f"only {ok.shape[0]} of {n} frames identified; the "
                f"sensor's covariance needs at least 10",
            )
        return cls(covariance=np.cov(ok, rowvar=False), identification_rate=r.identification_rate)

    def bind(self, channel: Channel) -> StarTrackerSensor:
        if channel.unit != "" or channel.size != 4:
            raise FieldError(
                f"sensors[{channel.name}]",
                "a star tracker measures the attitude channel "
                f"(4 Euler parameters, unit ''), not a channel of {channel.size} values in "
                f"{channel.unit!r}",
            )
        out = replace(self)
        object.__setattr__(out, "_acts", (False, True, False, False))
        return out

    def measure(self, v: FloatArray, noise: FloatArray | float) -> FloatArray:
        """β_m = δβ(L n) ⊗ β for true attitudes v (n_cases, 4) and noise (n_cases, 4)."""
        v = np.asarray(v, float)
        if v.shape[-1] != 4:
            raise FieldError(
                "attitude", f"a star tracker needs the 4 Euler parameters, got shape {v.shape}"
            )
        dtheta = np.asarray(noise, float)[..., :3] @ self._factor.T
        # exp(θ) of the plant's convention rotates the body by θ: C(exp θ) = exp(−[θ×])
        return quaternion_multiply(quaternion_exp(dtheta), v)
