"""The assembled model: dof bookkeeping, rigid-body vectors, per-node mode shapes, and mass
properties of an offset mass against the parallel-axis theorem (hand calculation; round-off
tolerances 1e-13 to 1e-14 relative)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flexsat.structures import Material, Section, Structure
from flexsat.structures.assembly import DOF_NAMES, DOF_SLOT

ALU = Material(E=70e9, rho=2700.0, nu=0.33)


def small_frame():
    """A clamped L-shaped frame of four nodes with a lumped mass at its corner."""
    s = Structure()
    for i, p in {0: (0, 0, 0), 1: (1.2, 0, 0), 2: (1.2, 0.9, 0), 3: (1.2, 0.9, 0.7)}.items():
        s.add_node(i, p)
    tube, rect = Section.tube(0.04, 0.002), Section.rectangle(0.03, 0.05)
    s.add_frame(0, 1, ALU, tube)
    s.add_frame(1, 2, ALU, rect, orientation=[0.3, 0.2, 1.0])
    s.add_frame(2, 3, ALU, tube)
    s.add_mass(2, 0.4)
    s.clamp(0)
    return s


def test_dof_slots_follow_the_dof_names():
    assert [DOF_SLOT[name] for name in DOF_NAMES] == list(range(6))


def test_assembly_bookkeeping():
    s = small_frame()
    asm = s.assemble()
    assert asm.n_dofs == 6 * 3 and asm.n_clamped == 6
    assert asm.dofs[asm.index(3, "ry")] == (3, "ry")
    assert abs(asm.K - asm.K.T).max() == 0 and abs(asm.M - asm.M.T).max() == 0
    R = asm.rigid_body_vectors(reference=(1.0, 2.0, 3.0))
    assert R[asm.index(2, "ux"), 5] == pytest.approx(-(0.9 - 2.0))  # (e_z × r)_x = -r_y
    modes = asm.modes(5)
    at = modes.at_nodes()
    assert at.shape == (5, 4, 6) and np.all(at[:, 0, :] == 0)  # node 0 clamped
    assert at[2, 3, 4] == modes.shapes[asm.index(3, "ry"), 2]
    assert modes.frequencies_hz == pytest.approx(modes.omegas / (2 * math.pi))
    with pytest.raises(ValueError, match=r"dof \(0, 'ux'\): not an active dof"):
        asm.index(0, "ux")


def test_offset_mass_has_its_own_mass_properties():
    """A lumped mass m with inertia J about its centre, carried at an offset r from a node,
    gives the structure m, a centre of mass at node + r and the inertia J about it (the
    parallel-axis theorem through R^T M R, an independent path)."""
    s = Structure()
    s.add_node(1, (0.3, -0.2, 0.1))
    r = np.array([0.4, 0.25, -0.6])
    J = np.array([[0.5, 0.02, 0.0], [0.02, 0.7, -0.03], [0.0, -0.03, 0.6]])
    s.add_mass(1, 3.0, inertia=J, offset=r)
    props = s.assemble().mass_properties(reference=(0.0, 0.0, 0.0))
    assert props["total_mass"] == pytest.approx(3.0, rel=1e-14)
    assert props["center_of_mass"] == pytest.approx((0.3, -0.2, 0.1) + r, rel=1e-14)
    assert np.allclose(props["inertia_center_of_mass"], J, rtol=0, atol=1e-13)
