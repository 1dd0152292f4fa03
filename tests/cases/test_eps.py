"""The Earth Pointing Satellite structure (EPS slew study c. 1989, L66-L136)."""

import json

import numpy as np
import pytest

from flexsat.cases.eps import NODE_ROLES, PUBLISHED, PUBLISHED_MODES, eps
from flexsat.units import to_si

PUBLISHED_HZ = np.array([to_si(f, "Hz") for _, f, _ in PUBLISHED_MODES])
# paper modes 7-20 (elastic 1-14): (component, motion) our describer must find
EXPECTED = [
    ("15 m antenna", "torsion about its axis"),
    ("15 m antenna", "z-rotation"),
    ("15 m antenna", "x-rotation"),
    ("7.5 m antenna", "torsion about its axis"),
    ("15 m antenna", "bending/elastic"),
    ("15 m antenna", "bending/elastic"),
    ("7.5 m antenna", "z-rotation"),
    ("7.5 m antenna", "x-rotation"),
] + [("15 m antenna", "bending/elastic")] * 6


@pytest.fixture(scope="module")
def case():
    return eps()


@pytest.fixture(scope="module")
def described(case):
    return case._classified(20)


def test_published_values_are_converted_with_pint(case):
    assert case.modulus == pytest.approx(275.9e9, rel=1e-12)
    assert case.density == 3250.0
    assert case.tube_outer_diameter == pytest.approx(0.051, rel=1e-12)
    assert case.tube_wall == pytest.approx(0.00159, rel=1e-12)
    assert case.section.A == pytest.approx(np.pi / 4 * (0.051**2 - 0.04782**2), rel=1e-12)
    assert case.mass_per_length == pytest.approx(0.8021, abs=1e-4)  # seed notes §1.1 [DERIVED]
    assert case.damping == 0.005


def test_layout_counts(case):
    """135 truss tubes (the published count), 36 per antenna, 4 supports each, 4 to the CG
    node; the paper's 95 nodes."""
    counts = case.element_counts
    assert counts["truss"] == PUBLISHED["truss_elements"] == 135
    assert counts["antenna 1"] == counts["antenna 2"] == 36
    assert counts["support 1"] == counts["support 2"] == PUBLISHED["support_elements"] == 4
    assert counts["actuator support"] == 4
    assert case.n_elements == 219  # the paper's deck has 223 (docs/eps.md)
    assert len(case.assembly.node_ids) == PUBLISHED["nastran_nodes"] == 95
    assert len(case.groups["truss"]) == 44
    assert len(case.groups["15 m antenna"]) == len(case.groups["7.5 m antenna"]) == 25


def test_total_mass_is_1028_kg_from_the_assembled_mass_matrix(case):
    props = case.mass_properties()
    assert props["total_mass"] == pytest.approx(1028.0, abs=1.0)
    b = case.mass_budget()
    assert b["total_assembled"] == pytest.approx(props["total_mass"], rel=1e-12)
    parts = (
        "truss",
        "antenna_1_structure",
        "antenna_2_structure",
        "antenna_supports",
        "actuator_support",
    )
    assert sum(b[p] for p in parts) == pytest.approx(b["structural"], rel=1e-12)
    assert b["structural"] + b["nonstructural"] + b["actuators"] == pytest.approx(1028.0, rel=1e-12)
    assert b["nonstructural"] == pytest.approx(329.63, rel=1e-12)
    assert b["antenna_1_nonstructural"] == pytest.approx(0.8 * 329.63, rel=1e-12)  # by area
    # documented deviations: structural mass within 1 % of 548 kg, actuators balance to 1028
    assert b["structural"] == pytest.approx(548.0, rel=0.01)
    assert b["actuators"] == pytest.approx(150.0, rel=0.04)
    assert b["truss"] == pytest.approx(
        0.8021 * (40 * 2.5 + 44 * 3 + 11 * 3 * 2**0.5 + 40 * np.hypot(2.5, 3)), rel=1e-4
    )


def test_torquer_node_is_at_the_centre_of_mass(case):
    props = case.mass_properties()
    roles = case.node_roles
    i = list(case.assembly.node_ids).index(roles[95])
    assert np.allclose(case.assembly.coordinates[i], props["center_of_mass"], atol=1e-9)
    assert np.allclose(props["center_of_mass"], case.center_of_mass, atol=1e-9)
    # principal inertia of order 1e5 kg m² (seed notes §1.4 estimate I_zz ≈ 0.8-1.5e5)
    assert 0.8e5 < props["inertia_center_of_mass"][2, 2] < 1.5e5


def test_exactly_six_rigid_body_modes(case):
    """Free-free: solved without telling the solver, exactly 6 modes are near zero."""
    modes = case.assembly.modes(12)
    f = modes.frequencies_hz
    assert np.sum(np.abs(f) < 1e-3) == 6
    assert f[6] > 0.2
    assert [str(d) for d in case._classified(1)[:6]] == ["rigid body"] * 6


def test_first_elastic_modes_have_the_published_character_and_order(described):
    got = [(d.component, d.motion) for d in described[6:20]]
    assert got == EXPECTED


def test_frequencies_within_25_percent_of_the_published_table(case):
    ratio = case.frequencies_hz(14) / PUBLISHED_HZ
    assert np.all(np.abs(ratio - 1) < 0.25), ratio
    # achieved: within 8 %
    assert np.all(np.abs(ratio - 1) < 0.08), ratio


def test_repeated_pairs_of_the_15_m_antenna(case):
    """Paper modes 11/12, 15/16, 19/20 are exact pairs here (12-fold symmetry, n = 2, 3, 4);
    17/18 are the two n = 1 modes, split 1 % by the 4-legged support (documented)."""
    f = case.frequencies_hz(14)
    for a, b in ((4, 5), (8, 9), (12, 13)):
        assert f[a] == pytest.approx(f[b], rel=1e-8)
    assert f[10] == pytest.approx(f[11], rel=0.015)


def test_first_twenty_elastic_modes_are_antenna_modes(described):
    """L127: 'the first 20 undamped elastic modes are all antenna modes'."""
    assert all(d.component.endswith("antenna") for d in described[6:26])


def test_first_truss_mode(case):
    """Published: about 7.0 Hz, the 50th elastic mode (L128-L129).  The mode number holds
    (50); the frequency does not: the published 3 m truss of 51 mm graphite tubes gives
    15.4 Hz (deviation documented in docs/eps.md; no tube/section tweak is made to hide it)."""
    number, f, text = case.first_truss_mode()
    assert number == PUBLISHED["first_truss_mode_number"]
    assert 14.0 < f < 17.0
    assert text.startswith("truss")


def test_node_roles_lie_on_the_right_components(case):
    roles = case.node_roles
    assert set(roles) == set(NODE_ROLES)
    coords = dict(zip(case.assembly.node_ids.tolist(), case.assembly.coordinates))
    groups = {k: set(v.tolist()) for k, v in case.groups.items()}
    hubs = {"15 m antenna": 45, "7.5 m antenna": 70}

    def radius(node, group):
        d = coords[node] - coords[hubs[group]]
        return np.hypot(d[0], d[2])  # in the antenna's x-z plane (boresight y)

    for paper, group, r in (
        (60, "15 m antenna", 7.5),
        (63, "15 m antenna", 7.5),
        (66, "15 m antenna", 7.5),
        (69, "15 m antenna", 7.5),
        (85, "7.5 m antenna", 3.75),
        (88, "7.5 m antenna", 3.75),
        (94, "7.5 m antenna", 3.75),
        (52, "15 m antenna", 3.75),
        (78, "7.5 m antenna", 1.875),
    ):
        assert roles[paper] in groups[group]
        assert radius(roles[paper], group) == pytest.approx(r, rel=1e-12)
    assert roles[95] in groups["torquers"]
    # with the default layout our numbering is the paper's
    assert all(roles[k] == k for k in roles)
    # 60/66 and 63/69 are diametrically opposite; 60 -> 63 is a quarter turn
    hub = coords[45]
    v = {k: (coords[k] - hub)[[0, 2]] for k in (60, 63, 66, 69)}
    assert np.allclose(v[60], -v[66]) and np.allclose(v[63], -v[69])
    assert abs(v[60] @ v[63]) < 1e-9


def test_mode_details_side_by_side_and_json_ready(case):
    d = case.mode_details(16)
    json.dumps(d)
    assert d["paper_mode_number"][:2] == [7, 8]
    assert d["published_hz"][0] == pytest.approx(0.2422)
    assert d["published_hz"][14] is None and d["ratio_to_published"][15] is None
    assert d["published_descriptions"][3] == "Torsion 7.5m Antenna"
    assert d["ratio_to_published"][0] == pytest.approx(case.frequencies_hz(1)[0] / 0.2422)
    assert d["node_roles"]["95"] == 95
    assert len(case.mode_descriptions(16)) == 16


def test_modal_model_has_half_percent_damping(case):
    mm = case.modal_model(20)
    assert mm.n_modes == 26
    assert np.all(mm.damping[:6] == 0) and np.allclose(mm.damping[6:], 0.005)
    assert mm.total_mass == pytest.approx(1028.0, abs=1.0)
    assert np.allclose(mm.frequencies_hz[6:], case.frequencies_hz(20), rtol=1e-10)


def test_overrides_accept_units(case):
    same = eps(small_support_height="500 cm", large_antenna_diameter="15000 mm")
    assert np.allclose(same.frequencies_hz(4), case.frequencies_hz(4), rtol=1e-10)
    lighter = eps(nonstructural_mass="300 kg")  # the actuators absorb the difference
    assert lighter.mass_properties()["total_mass"] == pytest.approx(1028.0, rel=1e-10)
    assert lighter.mass_budget()["actuators"] > case.mass_budget()["actuators"]
    published = eps(actuator_mass="150 kg")  # no balancing: total = structure + 329.63 + 150
    b = published.mass_budget()
    assert b["total_assembled"] == pytest.approx(b["structural"] + 329.63 + 150.0, rel=1e-10)
    flat = eps(depth_ratio=0)
    coords = flat.assembly.coordinates
    ids = list(flat.assembly.node_ids)
    assert coords[ids.index(60), 1] == pytest.approx(coords[ids.index(45), 1])


@pytest.mark.parametrize(
    "overrides,message",
    [
        ({"hub_inertia": 1}, "eps: unknown parameter"),
        ({"truss_length": "3 kg"}, "truss_length: incompatible units"),
        ({"large_support_height": -1}, "large_support_height: must be > 0"),
        ({"truss_bays": 2.5}, "truss_bays: must be a positive integer"),
        ({"small_antenna_bay": 11}, "small_antenna_bay: must be a bay number"),
        ({"small_antenna_bay": 1}, "small_antenna_bay: must differ"),
        ({"large_antenna_share": 1.5}, "large_antenna_share: must be in"),
        ({"total_mass": "500 kg"}, "actuator_mass: balancing to total_mass"),
        ({"tube_wall": "30 mm"}, "tube_wall: must be <="),
        ({"damping": 1.5}, "damping: must be a modal damping ratio"),
        ({"ribs": 2}, "ribs: must be >= 3"),
    ],
)
def test_bad_inputs_are_refused_by_name(overrides, message):
    with pytest.raises(ValueError, match=message):
        eps(**overrides)


def test_bad_mode_count_is_refused(case):
    with pytest.raises(ValueError, match="n_modes"):
        case.frequencies_hz(0)
    with pytest.raises(ValueError, match="n_modes: the model has"):
        case.frequencies_hz(10_000)


def test_plant_has_the_papers_final_actuators_and_rim_outputs():
    """Seed 003 L286-L295: torquers at the CG plus 69X, 63X, 66Y, 66Z, 60Y, 60Z, 88X; the goals
    bound the rim deflections of nodes 66, 69, 85, 88 (§3.2)."""
    from flexsat.cases.eps import eps

    case = eps()
    plant = case.plant(n_modes=10)
    assert [c.name for c in plant.inputs] == [
        "torque",
        "force_69X",
        "force_63X",
        "force_66Y",
        "force_66Z",
        "force_60Y",
        "force_60Z",
        "force_88X",
    ]
    rims = [c.name for c in plant.outputs if c.name.startswith("displacement_")]
    assert rims == [f"displacement_{n}{a}" for n in (66, 69, 85, 88) for a in "XYZ"]
    assert plant.nx == 7 + 2 * 10
    rigid = case.plant("rigid")
    np.testing.assert_array_equal(rigid.inertia, case.mass_properties()["inertia_center_of_mass"])
    with pytest.raises(ValueError, match="forces: 200 is not one of the paper's nodes"):
        case.plant(n_modes=2, forces=[(200, "x")])
    with pytest.raises(ValueError, match="model: must be 'flexible' or 'rigid'"):
        case.plant("floppy")
