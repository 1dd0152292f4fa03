"""Structures tested on their own (beams, the NAFEMS cross, the TAMU grid) as plants of the
simulation core: a point force at a node, the displacements of chosen nodes, modal damping.

A structure alone has no attitude to slew; what a user simulates on it is a forced or free
response (a hammer impulse, an initial modal amplitude, a shaker) with or without feedback,
so each such case offers the same channels: ``force`` (N) at one node along one axis and
``displacement_<node>`` (m) with its rate at the sensor nodes, on the modal model of its first
modes (:meth:`flexsat.dynamics.structural.StructuralPlant.from_modal_model`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy.typing as npt

from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant
from flexsat.input_checks import FieldError, require_count, require_nonneg
from flexsat.structures.modal_model import ModalModel

if TYPE_CHECKING:
    from flexsat.structures.fem import FEModes, Structure

_AXES = ("x", "y", "z")


def point_force_plant(
    modes: FEModes,
    force_node: int,
    sensor_nodes: Sequence[int],
    axis: str = "z",
    damping: float = 0.01,
    reference: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> StructuralPlant:
    """The plant of a finite-element solution with a point force and displacement sensors.

    Parameters
    ----------
    modes : flexsat.structures.fem.FEModes
        The modes to keep (rigid-body modes included for a free structure).
    force_node : int
        Node of the force input ``force`` (N), along ``axis``.
    sensor_nodes : sequence of int
        Nodes with outputs ``displacement_<node>`` (m) and ``displacement_<node>_dot`` (m/s)
        along ``axis``.
    axis : {"x", "y", "z"}
    damping : float
        Modal damping ratio of every elastic mode (default 1 %).
    reference : (3,)
        Reference point of the modal model (the support of a clamped structure), m.
    """
    if axis not in _AXES:
        raise FieldError("axis", f"must be one of {_AXES}, got {axis!r}")
    zeta = require_nonneg(damping, "damping", "")
    modal = ModalModel.from_fe(modes, damping=float(zeta), reference=reference)
    ids = set(modal.node_ids.tolist())
    for field, nodes in (("force_node", [force_node]), ("sensor_nodes", list(sensor_nodes))):
        for node in nodes:
            if node not in ids:
                raise FieldError(field, f"node {node!r} is not a node of the model")
    sensors = [Sensor(f"displacement_{n}", "displacement", n, axis) for n in sensor_nodes]
    sensors += [
        Sensor(f"displacement_{n}_dot", "displacement", n, axis, rate=True) for n in sensor_nodes
    ]
    return StructuralPlant.from_modal_model(
        modal, [Actuator("force", "force", force_node, axis)], sensors
    )


def first_modes(structure: Structure, n_modes: int, rigid_body_modes: int | None = None) -> FEModes:
    """The first ``n_modes`` modes (rigid ones included) of ``structure``."""
    n = require_count(n_modes, "n_modes")
    asm = structure.assemble()
    if n > asm.n_dofs:
        raise FieldError("n_modes", f"the model has {asm.n_dofs} dofs, got {n}")
    return asm.modes(n, rigid_body_modes=rigid_body_modes)


__all__ = ["first_modes", "point_force_plant"]
