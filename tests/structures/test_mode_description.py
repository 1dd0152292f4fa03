"""Automatic mode descriptions (flexsat.structures.mode_description) on a structure whose modes
are known in closed form: a light wheel on a massless shaft fixed to a heavy base."""

import numpy as np
import pytest

from flexsat.structures.fem import Structure
from flexsat.structures.mode_description import classify_modes, describe_modes
from flexsat.structures.sections import Material, Section

E = 200e9
I_BASE, M_BASE = 40.0, 200.0  # base block: mass (kg) and inertia (kg m²) at node 1
M_RIM, RADIUS, N_RIM = 1.0, 1.0, 8  # wheel: 8 point masses of 1 kg on a 1 m circle
SHAFT_LENGTH = 0.6
SHAFT = Section.rectangle(0.02, 0.03)  # Iz < Iy: bending about global y is the softer one
GROUPS = {"base": [1, 2, 3], "wheel": [4, *range(10, 10 + N_RIM)]}


def wheel_on_shaft() -> Structure:
    """Base (node 1) - massless shaft along x (nodes 1-4) - wheel hub (node 4) with massless
    spokes and rim in the y-z plane carrying the rim masses: I_wheel = 8 kg m² about x.  The
    wheel is 1e4 times stiffer than the shaft, so its modes are those of two rigid bodies to
    ~1e-4 below the wheel's own deformation modes."""
    massless, stiff, rim = Material(E, 0.0), Material(1e4 * E, 0.0), Section.tube(0.1, 0.005)
    s = Structure("wheel on shaft")
    for i in range(4):
        s.add_node(1 + i, (SHAFT_LENGTH / 3 * i, 0, 0))
    for i in range(3):
        s.add_frame(1 + i, 2 + i, massless, SHAFT)
    s.add_mass(1, M_BASE, [I_BASE] * 3)
    for k in range(N_RIM):
        a = 2 * np.pi * k / N_RIM
        s.add_node(10 + k, (SHAFT_LENGTH, RADIUS * np.cos(a), RADIUS * np.sin(a)))
        s.add_frame(4, 10 + k, stiff, rim)
    for k in range(N_RIM):
        s.add_frame(10 + k, 10 + (k + 1) % N_RIM, stiff, rim)
        s.add_mass(10 + k, M_RIM)
    return s


@pytest.fixture(scope="module")
def modes():
    return wheel_on_shaft().assemble().modes(16, rigid_body_modes=6)


@pytest.fixture(scope="module")
def described(modes):
    return classify_modes(modes, GROUPS)


def test_rigid_body_modes_are_named_and_shares_add_up(described):
    assert [str(d) for d in described[:6]] == ["rigid body"] * 6
    for d in described:
        assert sum(d.shares.values()) == pytest.approx(1.0, abs=1e-12)


def test_torsion_of_the_wheel_about_its_own_axis(described):
    """Two inertias on a torsion spring: ω² = k (1/I_w + 1/I_b), k = GJ/L; kinetic energy splits
    inversely to the inertias, so the wheel carries I_b / (I_w + I_b) = 40/48."""
    I_w = N_RIM * M_RIM * RADIUS**2
    k = Material(E, 0.0).shear_modulus * SHAFT.J / SHAFT_LENGTH
    d = described[6]
    assert d.frequency_hz == pytest.approx(
        np.sqrt(k * (1 / I_w + 1 / I_BASE)) / (2 * np.pi), rel=1e-3
    )
    assert d.component == "wheel" and d.motion == "torsion about its axis"
    assert d.share == pytest.approx(I_BASE / (I_w + I_BASE), rel=1e-6)
    assert d.rigid_fit == pytest.approx(1.0, abs=1e-6)
    assert str(d) == "wheel (83 %): torsion about its axis"


def test_rocking_is_named_after_the_global_axis_softer_one_first(described):
    """The shaft's softer bending (about global y) gives the lower rocking mode."""
    assert [d.motion for d in described[7:9]] == ["y-rotation", "z-rotation"]
    assert all(d.component == "wheel" for d in described[7:9])


def test_axial_mode_is_a_translation_with_the_two_mass_share(described):
    """Axial: ω² = EA/L (1/m_w + 1/m_b), wheel share m_b / (m_w + m_b)."""
    m_w = N_RIM * M_RIM
    axial = [d for d in described if d.motion == "translation along x"]
    assert len(axial) == 1
    d = axial[0]
    k = E * SHAFT.A / SHAFT_LENGTH
    assert d.frequency_hz == pytest.approx(
        np.sqrt(k * (1 / m_w + 1 / M_BASE)) / (2 * np.pi), rel=1e-3
    )
    assert d.share == pytest.approx(M_BASE / (m_w + M_BASE), rel=1e-6)


def test_wheel_deformation_is_bending_in_repeated_pairs(described):
    elastic = described[12:16]
    assert all(d.component == "wheel" and d.motion == "bending/elastic" for d in elastic)
    assert all(d.rigid_fit < 0.01 for d in elastic)
    assert elastic[0].frequency_hz == pytest.approx(elastic[1].frequency_hz, rel=1e-8)


def test_describe_modes_returns_the_phrases(modes, described):
    assert describe_modes(modes, GROUPS) == [str(d) for d in described]


def test_explicit_axis_overrides_the_symmetry_axis(modes):
    """With the wheel's axis declared along y, the rocking about y becomes its 'torsion' and
    the true torsion (about x) an x-rotation."""
    d = classify_modes(modes, GROUPS, axes={"wheel": (0, 1, 0)})
    assert d[6].motion == "x-rotation"
    assert d[7].motion == "torsion about its axis"


def test_nodes_in_no_group_form_other(modes):
    d = classify_modes(modes, {"wheel": GROUPS["wheel"]})
    assert set(d[6].shares) == {"wheel", "other"}
    assert d[6].shares["other"] == pytest.approx(1 - d[6].share, abs=1e-12)
    only_base = classify_modes(modes, {"hub": [4]})
    assert str(only_base[6]).startswith("other (")


def test_rigid_fraction_threshold_decides_bending(modes):
    """A mode is 'bending/elastic' exactly when the rigid fit of its component is below the
    threshold."""
    for threshold in (0.2, 0.5, 0.99, 1.0):
        for d in classify_modes(modes, GROUPS, rigid_fraction=threshold)[6:]:
            assert (d.motion == "bending/elastic") == (d.rigid_fit < threshold)


@pytest.mark.parametrize(
    "groups,message",
    [
        ({}, "groups: must be a non-empty dict"),
        ({"a": []}, "groups: group 'a' is empty"),
        ({"a": [1, 99]}, "groups: group 'a': node 99 is not in the model"),
        ({"a": [1, 2], "b": [2, 3]}, "groups: node 2 is in both 'a' and 'b'"),
        ({"other": [1]}, "groups: names must be"),
    ],
)
def test_bad_groups_are_refused_by_name(modes, groups, message):
    with pytest.raises(ValueError, match=message):
        describe_modes(modes, groups)


def test_bad_options_are_refused_by_name(modes):
    with pytest.raises(ValueError, match="rigid_tol"):
        describe_modes(modes, GROUPS, rigid_tol=-1)
    with pytest.raises(ValueError, match="rigid_fraction"):
        describe_modes(modes, GROUPS, rigid_fraction=0)
    with pytest.raises(ValueError, match="axes: unknown component"):
        describe_modes(modes, GROUPS, axes={"hub": (1, 0, 0)})
    with pytest.raises(ValueError, match="axes: the axis of 'wheel'"):
        describe_modes(modes, GROUPS, axes={"wheel": (0, 0, 0)})


def test_plane_grid_model_with_three_dofs_per_node():
    """A grid cantilever (dofs uz, rx, ry only): no symmetry axis is inferred, the tip segment
    of the first bending mode translates along z."""
    s = Structure("grid cantilever")
    for i in range(5):
        s.add_node(i + 1, (float(i), 0.0, 0.0))
    for i in range(4):
        s.add_grid(
            i + 1, i + 2, EI=1e4, GJ=1e4, mass_per_length=1.0, torsional_inertia_per_length=0.1
        )
    s.clamp(1)
    d = classify_modes(s.assemble().modes(4), {"root": [1, 2, 3], "tip": [4, 5]})
    assert str(d[0]).startswith("tip (") and d[0].motion == "translation along z"
    assert all(sum(x.shares.values()) == pytest.approx(1.0) for x in d)
