"""An SI finite-element description (structures/fe_description.py) builds the structure a user
would build call by call, and refuses a bad entry by its path."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.input_checks import FieldError
from flexsat.structures import Material, Section, Structure
from flexsat.structures.fe_description import (
    ClampSpec,
    ElementSpec,
    FEDescription,
    MassSpec,
    NodeSpec,
    RigidLinkSpec,
)

ALU = Material(E=70e9, rho=2700.0, nu=0.33)
TUBE = Section.tube(0.03, 0.001)


def triangle(**changes) -> FEDescription:
    """Three frames and a rod in a triangle with a lumped mass at an offset."""
    values = dict(
        nodes=[NodeSpec(1, (0, 0, 0)), NodeSpec(2, (1, 0, 0)), NodeSpec(3, (0.5, 0.8, 0.1))],
        materials={"alu": ALU},
        sections={"tube": TUBE},
        elements=[
            ElementSpec("frame", (1, 2), "alu", "tube", orientation=(0, 0, 1)),
            ElementSpec("frame", (2, 3), "alu", "tube", offsets=((0, 0, 0.01), (0, 0, 0))),
            ElementSpec("frame", (3, 1), "alu", "tube", lumped=True),
            ElementSpec("rod", (1, 2), "alu", "tube"),
        ],
        masses=[MassSpec(3, 2.0, inertia=(0.1, 0.2, 0.3), offset=(0, 0, 0.2))],
        n_modes=5,
        damping=0.02,
    )
    return FEDescription(**(values | changes))


def by_hand() -> Structure:
    s = Structure()
    for node, xyz in ((1, (0, 0, 0)), (2, (1, 0, 0)), (3, (0.5, 0.8, 0.1))):
        s.add_node(node, xyz)
    s.add_frame(1, 2, ALU, TUBE, orientation=(0, 0, 1))
    s.add_frame(2, 3, ALU, TUBE, offsets=((0, 0, 0.01), (0, 0, 0)))
    s.add_frame(3, 1, ALU, TUBE, lumped=True)
    s.add_rod(1, 2, ALU, TUBE.A)
    s.add_mass(3, 2.0, inertia=(0.1, 0.2, 0.3), offset=(0, 0, 0.2))
    return s


def test_the_description_builds_the_structure_built_by_hand():
    """Bit for bit: the same calls in the same order."""
    got, expected = triangle().structure().assemble(), by_hand().assemble()
    assert got.dofs == expected.dofs
    assert (got.K != expected.K).nnz == 0 and (got.M != expected.M).nnz == 0


def test_a_free_description_has_six_rigid_modes_then_its_elastic_ones():
    modal = triangle().modal_model()
    expected = by_hand().assemble().modes(11, rigid_body_modes=6)
    assert modal.boundary == "free"
    np.testing.assert_array_equal(modal.frequencies, expected.omegas)
    np.testing.assert_array_equal(modal.damping, np.r_[np.zeros(6), np.full(5, 0.02)])


def test_a_clamped_description_is_referenced_at_its_first_clamp():
    modal = triangle(clamps=[ClampSpec(2), ClampSpec(1, ("ux", "uy", "uz"))]).modal_model()
    assert modal.boundary == "cantilevered"
    assert modal.frequencies[0] > 0
    np.testing.assert_array_equal(modal.reference, (1.0, 0.0, 0.0))


@pytest.mark.parametrize(
    "changes, field, rule",
    [
        (
            {"elements": [ElementSpec("frame", (1, 2), "steel", "tube")]},
            "elements[0].material",
            "unknown material 'steel'",
        ),
        (
            {"elements": [ElementSpec("frame", (1, 9), "alu", "tube")]},
            "elements[0].nodes",
            "unknown node 9",
        ),
        (
            {"elements": [ElementSpec("frame", (1, 1), "alu", "tube")]},
            "elements[0].nodes",
            "two different nodes",
        ),
        (
            {"elements": [ElementSpec("beam2d", (1, 2), "alu", "tube")]},
            "elements[0].kind",
            "must be one of",
        ),
        (
            {"elements": [ElementSpec("rod", (1, 2), "alu", "tube", orientation=(0, 0, 1))]},
            "elements[0].orientation",
            "a rod has no orientation",
        ),
        (
            {"elements": [ElementSpec("frame", (1, 2), "alu", "tube", orientation=(1, 0, 0))]},
            "elements[0].orientation",
            "parallel",
        ),
        (
            {"elements": [ElementSpec("frame", (1, 2), "alu", "tube", orientation=(0, 0, 0))]},
            "elements[0].orientation",
            "nonzero",
        ),
        ({"masses": [MassSpec(4, 1.0)]}, "masses[0].node", "unknown node 4"),
        ({"masses": [MassSpec(1, 1.0, offset=(1, 0))]}, "masses[0].offset", "3 components"),
        (
            {"masses": [MassSpec(1, 1.0, inertia=(4.0, 1.6, 1.8))]},
            "masses[0].inertia",
            "violate the triangle inequality I1 + I2 >= I3",
        ),
        (
            {"masses": [MassSpec(1, 1.0, inertia=(0.0, 0.0, 1.0))]},  # planar: not a body
            "masses[0].inertia",
            "triangle inequality",
        ),
        ({"rigid_links": [RigidLinkSpec(1, (5,))]}, "rigid_links[0].nodes", "unknown node 5"),
        ({"rigid_links": [RigidLinkSpec(1, ())]}, "rigid_links[0].nodes", "at least one"),
        (
            {"rigid_links": [RigidLinkSpec(1, (3,)), RigidLinkSpec(2, (3,))]},
            "rigid_links[1].dependent",
            "already rigidly linked",
        ),
        ({"clamps": [ClampSpec(1, "none")]}, "clamps[0].dofs", "'all' or a list"),
        ({"clamps": [ClampSpec(1, ("uw",))]}, "clamps[0].dofs", "unknown dof 'uw'"),
        ({"nodes": [NodeSpec(1, (0, 0, 0)), NodeSpec(1, (1, 0, 0))]}, "nodes[1]", "duplicate"),
        ({"nodes": [NodeSpec(1.5, (0, 0, 0))]}, "nodes[0].id", "must be an integer"),
    ],
)
def test_a_bad_entry_is_refused_at_its_path(changes, field, rule):
    with pytest.raises(FieldError) as info:
        triangle(**changes).structure()
    assert info.value.field == field
    assert rule in info.value.rule


@pytest.mark.parametrize(
    "changes, field, rule",
    [
        ({"damping": [0.01, 0.02]}, "damping", "one per elastic mode (5)"),
        ({"damping": -0.1}, "damping", ">= 0"),
        ({"n_modes": 0}, "n_modes", ""),
        ({"materials": {"alu": "aluminium"}}, "materials.alu", "must be a Material"),
    ],
)
def test_bad_settings_are_refused(changes, field, rule):
    with pytest.raises(FieldError) as info:
        triangle(**changes)
    assert info.value.field == field and rule in info.value.rule


def test_more_modes_than_dofs_are_refused():
    with pytest.raises(FieldError, match="n_modes: the model has 18 dofs, so at most 12"):
        triangle(n_modes=13).modal_model()


def test_a_mechanism_is_refused_as_the_structure():
    """Two rods hinged at a free node: the clamped structure can swing."""
    with pytest.raises(FieldError) as info:
        FEDescription(
            nodes=[NodeSpec(1, (0, 0, 0)), NodeSpec(2, (1, 0, 0))],
            materials={"alu": ALU},
            sections={"tube": TUBE},
            elements=[ElementSpec("rod", (1, 2), "alu", "tube")],
            masses=[MassSpec(2, 1.0)],
            clamps=[ClampSpec(1)],
            n_modes=1,
        ).modal_model()
    assert info.value.field == "structure" and "mechanism" in info.value.rule


def test_a_rigid_link_ties_a_node_to_its_independent_node():
    """Node 4 on a rigid bracket from node 1: its shapes are node 1's rigid motion."""
    description = triangle(
        nodes=[*triangle().nodes, NodeSpec(4, (0.0, -0.3, 0.2))],
        rigid_links=[RigidLinkSpec(1, (4,))],
    )
    modal = description.modal_model()
    shapes = {int(n): modal.shapes[:, i] for i, n in enumerate(modal.node_ids)}
    r = np.array([0.0, -0.3, 0.2])
    moved = shapes[1][:, :3] + np.cross(shapes[1][:, 3:], r)
    np.testing.assert_allclose(shapes[4][:, :3], moved, rtol=0, atol=1e-14)
    np.testing.assert_allclose(shapes[4][:, 3:], shapes[1][:, 3:], rtol=0, atol=1e-14)


def test_a_loose_node_is_refused_as_the_structure():
    """A node no element, mass or link touches: refused when the structure is assembled."""
    with pytest.raises(FieldError) as info:
        triangle(nodes=[*triangle().nodes, NodeSpec(4, (0.0, -0.3, 0.2))]).modal_model()
    assert info.value.field == "structure"
    assert "node 4: not connected" in info.value.rule
