r"""Every linear law as a python-control ``StateSpace`` with labelled signals (issue 24).

Two forms, both from the measurements the law reads to the commands it writes, the feedback
sign included (u = K y; a PD law is K = [−kp, −kd]) and the references left out (they do not
enter the loop transfer):

* :func:`discrete_law` — exactly what runs: the law's compiled-loop form
  (:mod:`~flexsat.control.linear_form`, :math:`\xi_{k+1} = A_k\xi_k + B_k e_k`,
  :math:`u_k = C_k\xi_k + D_k e_k`) at the control period, which already contains the law's own
  zero-order hold (an LQG estimator propagated exactly over the period with u and y held), then
  a computation delay of d samples on the commands, state-augmented
  (:func:`~flexsat.analysis.frequency_domain.delay_outputs`). Combined with the plant's exact
  ZOH equivalent it is the sampled-data loop.
* :func:`continuous_law` — the design's continuous form where the law has one: a static gain
  (PD, the Lyapunov Law I/II gains: the same in both forms), the continuous LQG compensator
  :math:`\dot{\hat x} = (A - BK - LC)\hat x + Ly`, :math:`u = -K\hat x` (Hailey, Sortun &
  Agrawal c. 1992, Eqs. 38–45), a continuous python-control system behind a
  :class:`~flexsat.control.state_space_compensator.StateSpaceCompensator` (PPF banks), and
  :meth:`AttitudeLQG.compensator <flexsat.control.mimo_lqg.AttitudeLQG.compensator>`.

Signals carry python-control names: a channel one value wide by its name (``theta``), a wider
one as ``name[i]`` (``torque[0]``), the convention of
:meth:`~flexsat.dynamics.attitude_linearization.AttitudeLinearization.to_statespace` and of
:func:`~flexsat.dynamics.linear_model.plant_state_space`, so law and plant connect by name.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, TypeGuard

import numpy as np

from flexsat.analysis.frequency_domain import delay_outputs
from flexsat.control.base import Controller
from flexsat.input_checks import FieldError, require_positive

if TYPE_CHECKING:
    import control as ct
    from flexsat.control.mimo_lqg import AttitudeLQG
    from flexsat.units import QuantityArrayLike

__all__ = ["channel_labels", "continuous_law", "discrete_law"]


def channel_labels(names: Sequence[str], sizes: Sequence[int]) -> list[str]:
    """python-control signal names of channels: ``name`` (width 1) or ``name[i]``."""
    labels: list[str] = []
    for name, size in zip(names, sizes):
        labels += [name] if size == 1 else [f"{name}[{i}]" for i in range(size)]
    return labels


def _sizes(law: Controller, attr: str, names: Sequence[str]) -> tuple[int, ...]:
    return tuple(getattr(law, attr, (1,) * len(names)))


def _require_law(law: object) -> Controller:
    if not isinstance(law, Controller):
        raise FieldError("law", f"must be a flexsat Controller, got {type(law).__name__}")
    return law


def _attitude_lqg(law: Controller) -> TypeGuard[AttitudeLQG]:
    from flexsat.control.mimo_lqg import AttitudeLQG

    return isinstance(law, AttitudeLQG)


def discrete_law(law: Controller, dt: QuantityArrayLike, delay: int = 0) -> ct.StateSpace:
    """The law as it runs, a discrete ``StateSpace`` at period dt with d samples of delay.

    Parameters
    ----------
    law : Controller
        A law with a constant linear form (or an AttitudeLQG, whose compensator is linear in
        its attitude error).
    dt : float, str or Quantity
        Control period, s.
    delay : int
        Computation delay, whole samples, on every command.

    Raises
    ------
    FieldError
        For a nonlinear law (no linear form), a time-varying one (a scheduled gain), or per-case
        gains (export one case).
    """
    import control as ct

    law = _require_law(law)
    h = float(require_positive(dt, "dt", "s"))
    if _attitude_lqg(law):
        if abs(law.dt - h) > 1e-6 * h:
            raise FieldError("dt", f"the law was built for {law.dt:g} s, asked for {h:g} s")
        Phi, Gu, Gy = law.estimator
        comp = law.compensator()
        sys = ct.ss(
            Phi - Gu @ law.K,
            Gy,
            -law.K,
            np.zeros((law.K.shape[0], Gy.shape[1])),
            h,
            states=comp.state_labels,
            inputs=comp.input_labels,
            outputs=comp.output_labels,
            name=type(law).__name__,
        )
        return delay_outputs(sys, delay)
    form = law.linear_form(h, np.array([0.0, h]), 1)
    if form is None:
        raise FieldError(
            "law", f"{type(law).__name__} is nonlinear (it has no linear form) to export"
        )
    for name in ("Ak", "Bk", "Ck", "Dk"):
        arr = getattr(form, name)
        if arr.shape[0] != 1:
            raise FieldError(
                "law",
                f"{type(law).__name__} is time-varying ({name} is scheduled): a transfer "
                "function needs constant gains",
            )
        if arr.shape[1] != 1:
            raise FieldError(
                "law", f"{type(law).__name__} has per-case gains ({name}): export one case"
            )
    nk = form.n_states
    sys = ct.ss(
        form.Ak[0, 0],
        form.Bk[0, 0],
        form.Ck[0, 0],
        form.Dk[0, 0],
        h,
        states=[f"xi[{i}]" for i in range(nk)],
        inputs=channel_labels(form.reads, form.read_sizes),
        outputs=channel_labels(form.writes, form.write_sizes),
        name=type(law).__name__,
    )
    return delay_outputs(sys, delay)


def continuous_law(law: Controller) -> ct.StateSpace:
    """The law's continuous design form (module docstring).

    Raises
    ------
    FieldError
        For a law designed in discrete time or with no continuous form (name and reason).
    """
    import control as ct
    from flexsat.control.lqg import LQGController
    from flexsat.control.state_space_compensator import StateSpaceCompensator

    law = _require_law(law)
    name = type(law).__name__
    if _attitude_lqg(law):
        return law.compensator()
    if isinstance(law, StateSpaceCompensator):
        sys = law.system
        if sys.dt not in (0, None):
            raise FieldError("law", f"{name} is defined in discrete time: use discrete_law")
        return ct.ss(
            sys.A,
            sys.B,
            sys.C,
            sys.D,
            inputs=channel_labels(law.reads, law.read_sizes),
            outputs=channel_labels(law.writes, law.write_sizes),
            name=name,
        )
    if type(law) is LQGController:
        if law.gains != "continuous":
            raise FieldError("law", f"{name} has discrete gains: use discrete_law")
        A, B, C, K, L = law.A, law.B, law.C, law.K, law.L
        return ct.ss(
            A - B @ K - L @ C,
            L,
            -K,
            np.zeros((1, C.shape[0])),
            states=[f"x_hat[{i}]" for i in range(A.shape[0])],
            inputs=channel_labels(law.reads, _sizes(law, "read_sizes", law.reads)),
            outputs=channel_labels(law.writes, _sizes(law, "write_sizes", law.writes)),
            name=name,
        )
    # a static law: its gain is the same in continuous and discrete time
    period = 1.0
    form = law.linear_form(period, np.array([0.0, period]), 1)
    if form is not None and form.n_states == 0:
        if form.Dk.shape[:2] != (1, 1):
            raise FieldError(
                "law", f"{name} has scheduled or per-case gains: export one constant case"
            )
        return ct.ss(
            np.zeros((0, 0)),
            np.zeros((0, form.p)),
            np.zeros((form.m, 0)),
            form.Dk[0, 0],
            inputs=channel_labels(form.reads, form.read_sizes),
            outputs=channel_labels(form.writes, form.write_sizes),
            name=name,
        )
    raise FieldError(
        "law",
        f"{name} has no continuous form flexsat knows (a static gain, an LQG with continuous "
        "gains, a continuous StateSpaceCompensator, an AttitudeLQG): use discrete_law",
    )
