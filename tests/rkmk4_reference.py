"""The reference loop over the rigid body's RKMK4 kernel for its tests (order, conservation,
Euler-Poinsot, torque laws at the stages): the kernel is the one-step map of the plants' own
step, which the engine calls once per substep; this loop exists only to test it."""

import numpy as np

from flexsat.dynamics import attitude as att
from flexsat.dynamics.attitude import case_shape, require_quaternion, require_shape
from flexsat.dynamics.rigid_body import dexpinv, euler_acceleration, require_inertia, rkmk4_step
from flexsat.input_checks import require_numeric


def propagate(beta0, w0, inertia, t, torque=None) -> tuple[np.ndarray, np.ndarray]:
    r"""Propagate (β, ω) of a rigid body over the time grid ``t`` by the engine's RKMK4 kernel
    (:func:`flexsat.dynamics.rigid_body.rkmk4_step`), one step per grid interval.

    The global error is :math:`O(h^4)`: for a torque-free body with rates |ω| ~ 1 rad/s,
    h = 5 ms gives ω to ~2e-10 after 100 s (measured in the tests); ‖β‖ − 1 stays at
    round-off.

    Parameters
    ----------
    beta0 : array_like, shape (..., 4)
        Initial unit Euler parameters (inertial to body).
    w0 : array_like, shape (..., 3)
        Initial body angular velocity (rad/s).
    inertia : array_like, shape (..., 3, 3)
        Inertia about the centre of mass, body axes (kg·m²).
    t : array_like, shape (n_t,)
        Strictly increasing times (s); the state at ``t[0]`` is the initial one.
    torque : None, array_like of shape (..., 3), or callable
        External torque in body components (N·m): constant, or ``torque(t, beta, w)``
        returning (..., 3), called at the RK stages (and once up front, to check its
        output).

    Returns
    -------
    beta : ndarray, shape (..., n_t, 4)
    w : ndarray, shape (..., n_t, 3)
    """
    b = require_quaternion(beta0, "beta0")
    w = require_shape(w0, "w0", (3,))
    J = require_inertia(inertia)
    t = require_numeric(t, "t")
    if t.ndim != 1 or t.size < 1 or np.any(np.diff(t) <= 0):
        raise ValueError(f"t: must be a 1-D strictly increasing time grid, got shape {t.shape}")
    u_const = (
        np.zeros(3) if torque is None or callable(torque) else require_shape(torque, "torque", (3,))
    )
    shape = case_shape(
        beta0=b.shape[:-1], w0=w.shape[:-1], inertia=J.shape[:-2], torque=u_const.shape[:-1]
    )
    b = np.broadcast_to(b, shape + (4,)).copy()
    w = np.broadcast_to(w, shape + (3,)).copy()
    Jinv = np.linalg.inv(J)
    u_of = torque if callable(torque) else (lambda tt, bb, ww: u_const)
    if callable(torque):  # one call up front, so a wrong law fails here, naming itself
        u0 = require_shape(torque(t[0], b, w), "torque(t, beta, w)", (3,))
        try:
            np.broadcast_shapes(u0.shape, shape + (3,))
        except ValueError:
            raise ValueError(
                f"torque(t, beta, w): must return shape {shape + (3,)} (one torque "
                f"per case), got {u0.shape}"
            ) from None

    betas = np.empty(shape + (t.size, 4))
    ws = np.empty(shape + (t.size, 3))
    betas[..., 0, :], ws[..., 0, :] = b, w
    zero = np.zeros(shape + (3,))

    def stage(tt, th, ww):
        bb = (
            att.quaternion_multiply(att.quaternion_exp(th), b) if callable(torque) else b
        )  # β only read by a torque law
        return dexpinv(th, ww), euler_acceleration(ww, J, Jinv, u_of(tt, bb, ww))

    # a non-finite state is caught and reported below, naming the cases: no warnings first
    with np.errstate(over="ignore", invalid="ignore"):
        for n in range(t.size - 1):
            h, tn = t[n + 1] - t[n], t[n]
            b, w = rkmk4_step(b, w, h, lambda tau, th, ww, tn=tn: stage(tn + tau, th, ww), zero)
            if not (np.all(np.isfinite(w)) and np.all(np.isfinite(b))):
                bad = ~(np.isfinite(w).all(-1) & np.isfinite(b).all(-1))
                cases = [tuple(int(i) for i in c) for c in np.argwhere(np.atleast_1d(bad))][:10]
                raise ValueError(
                    f"propagate: the state became non-finite at t = {t[n + 1]:.6g} s "
                    f"(case index {cases}): a non-finite torque, or rates too large "
                    f"for the step {h:.3g} s"
                )
            betas[..., n + 1, :], ws[..., n + 1, :] = b, w
    return betas, ws
