r"""A plant's linear part as a python-control ``StateSpace`` with labelled signals (issue 24).

:math:`\dot x = A x + B u`, :math:`y = C x + D u` from :meth:`~flexsat.dynamics.plant.Plant.
linear_part` and the output matrices of the chosen linear outputs
(:meth:`~flexsat.dynamics.plant.Plant.output_matrices`). Signals are named as python-control
names vector signals: a channel one value wide by its name, a wider one ``name[i]``; states are
``x[i]`` unless the plant labels them. A plant with a nonlinear force is refused, naming the
way to linearise it (:func:`~flexsat.dynamics.attitude_linearization.linearize_attitude`), and
so is a dispersed batch (one case at a time).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from flexsat.input_checks import FieldError

if TYPE_CHECKING:
    import control as ct
    from flexsat.dynamics.plant import Plant

__all__ = ["plant_state_space"]


def _labels(name: str, size: int) -> list[str]:
    return [name] if size == 1 else [f"{name}[{i}]" for i in range(size)]


def plant_state_space(
    plant: Plant,
    outputs: Sequence[str] | None = None,
    name: str | None = None,
    states: Sequence[str] | None = None,
) -> ct.StateSpace:
    """The plant's linear part with its linear outputs (module docstring).

    Parameters
    ----------
    plant : Plant
        A linear plant with one case.
    outputs : sequence of str, optional
        Output channels to keep, in order; default every linear output but ``state``.
    name : str, optional
        The system's python-control name (default the plant's class name).
    states : sequence of str, optional
        State labels (default ``x[i]``); label a coordinate ``q`` and its rate ``q_dot`` so
        that :func:`~flexsat.analysis.loop_modes.closed_loop_poles` groups them as one mode.

    Raises
    ------
    FieldError
        For a nonlinear or dispersed plant, an unknown output or one that is not linear.
    """
    import control as ct
    from flexsat.dynamics.plant import Plant

    if not isinstance(plant, Plant):
        raise FieldError("plant", f"must be a flexsat Plant, got {type(plant).__name__}")
    kind = type(plant).__name__
    if plant.nonlinear:
        raise FieldError(
            "plant",
            f"{kind} is nonlinear: linearise it first (linearize_attitude for a spacecraft)",
        )
    A, B = (np.asarray(M, float) for M in plant.linear_part())
    if A.ndim != 2:
        raise FieldError("plant", f"{kind} is a dispersed batch: export one case at a time")
    known = {c.name: c for c in plant.outputs}
    if outputs is None:
        chosen = [
            c.name for c in plant.outputs if c.name != "state" and plant.output_matrices(c.name)
        ]
    else:
        chosen = list(outputs)
    rows_C, rows_D, labels = [], [], []
    for out in chosen:
        if out not in known:
            raise FieldError("outputs", f"{out!r} is not an output of {kind} ({sorted(known)})")
        mats = plant.output_matrices(out)
        if mats is None:
            raise FieldError("outputs", f"{out!r} is not a linear output of {kind}")
        C, D, _ = mats
        rows_C.append(np.atleast_2d(C))
        rows_D.append(np.atleast_2d(D))
        labels += _labels(out, known[out].size)
    if not labels:
        raise FieldError("outputs", f"{kind} has no linear output to export")
    in_labels = [lab for c in plant.inputs for lab in _labels(c.name, c.size)]
    state_labels = [f"x[{i}]" for i in range(plant.nx)] if states is None else list(states)
    if len(state_labels) != plant.nx or len(set(state_labels)) != plant.nx:
        raise FieldError("states", f"give {plant.nx} distinct labels, got {len(state_labels)}")
    return ct.ss(
        A,
        B,
        np.vstack(rows_C),
        np.vstack(rows_D),
        states=list(state_labels),
        inputs=in_labels,
        outputs=labels,
        name=name or kind,
    )
