"""The ``model:`` section of a simulation scenario (scenarios/models.py): one's own structure.

Acceptance: the same structure -- a 20 kg hub with two 2 m aluminium booms and offset tip
masses, free-free, and a clamped aluminium tube with a tip mass -- given (a) through the Python
API (Structure -> modes -> ModalModel.from_fe), (b) as an inline finite-element description in
YAML, (c) as a ModalModel netCDF file and (d) as a universal file gives the same modes:

- (a), (b), (c): frequencies to 1e-12 relative, shapes to 1e-9 of their largest entry. (b)
  assembles the same matrices from SI numbers that may differ from the API's by one rounding of
  the unit conversion (400 mm -> 0.4 m) and runs the same eigen-solver: the eigenvalues move by
  O(ε κ), the eigenvectors by O(ε λ_max / gap) (Davis-Kahan), λ_max/gap ~ 1e5 with the stiff
  hub arms, 1.2e-11 observed; (c) is a float64 round trip (exact);
- (d) to the universal file's six significant digits (datasets 15 and 55 store six): frequencies
  to 5e-6 relative, shapes to 5e-6 of their largest entry;

The L-shaped frames of tests/data/op2 (pyNastran-written plain SOL 103 OP2s, float32 values)
equal their inline description to 1e-6 (e). Shapes are compared up to sign: the hub-boom
modes are distinct (rectangular booms, distinct hub inertias); the tube's bending pairs are
repeated, but its inline description converts to the very floats of the API's (checked: the
shapes agree exactly), so the same solve returns the same vectors of each pair. Every refusal
names its field path.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
from flexsat.dynamics.hub_appendage import HubAppendage, HubAppendageParams
from flexsat.dynamics.structural import StructuralPlant
from flexsat.scenarios import ScenarioError, load_scenario, run_scenario
from flexsat.scenarios.simulation import build_plant
from flexsat.structures import Material, ModalModel, Section, Structure, TipMassCantilever
from flexsat.structures.io_uff import write_modal_uff

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels

ALU = Material(E=70e9, rho=2700.0, nu=0.33)
ARM = Material(E=200e9, rho=0.0)  # massless stiff arms from the hub node to the boom roots
BOOM = Section.rectangle(0.04, 0.02)
ARM_SECTION = Section.tube(0.1, 0.01)
TUBE = Section.tube(0.03, 0.001)
HUB_INERTIA = [0.6, 0.5, 0.7]
TIP_OFFSET = [0.0, 0.0, 0.05]

#: rounding of a universal file (six significant digits)
UFF_RTOL = 5e-6
#: (a), (b), (c): the same arithmetic up to a rounding of the inputs (module docstring)
SAME_RTOL = 1e-12
SAME_SHAPE_TOL = 1e-9


# -- (a) the Python API ------------------------------------------------------------------------
def hub_booms_api() -> ModalModel:
    s = Structure()
    s.add_node(0, (0.0, 0.0, 0.0))
    for side, first in ((1.0, 100), (-1.0, 200)):
        for k in range(5):
            s.add_node(first + k, (side * (0.4 + 0.5 * k), 0.0, 0.0))
    for first in (100, 200):
        s.add_frame(0, first, ARM, ARM_SECTION)
        for k in range(4):
            s.add_frame(first + k, first + k + 1, ALU, BOOM, orientation=(0, 0, 1))
    s.add_mass(0, 20.0, inertia=HUB_INERTIA)
    s.add_mass(104, 1.0, inertia=[1e-3] * 3, offset=TIP_OFFSET)
    s.add_mass(204, 1.0, inertia=[1e-3] * 3, offset=TIP_OFFSET)
    modes = s.assemble().modes(6 + 8, rigid_body_modes=6)
    return ModalModel.from_fe(modes, damping=np.r_[np.zeros(6), np.full(8, 0.005)], boundary="free")


def clamped_tube_api() -> ModalModel:
    s = Structure()
    for k in range(11):
        s.add_node(k, (0.2 * k, 0.0, 0.0))
    for k in range(10):
        s.add_frame(k, k + 1, ALU, TUBE)
    s.add_mass(10, 0.5)
    s.clamp(0)
    return ModalModel.from_fe(s.assemble().modes(6), damping=0.01, reference=(0.0, 0.0, 0.0))


# -- (b) the same in YAML ----------------------------------------------------------------------
def hub_booms_fe() -> dict:
    nodes = [{"id": 0, "xyz": [0, 0, 0]}]
    elements = []
    for side, first in ((1, 100), (-1, 200)):
        nodes += [
            {"id": first + k, "xyz": [f"{side * (400 + 500 * k)} mm", "0 m", 0]} for k in range(5)
        ]
        elements.append({"nodes": [0, first], "material": "arm_steel", "section": "arm"})
        elements += [
            {
                "kind": "frame",
                "nodes": [first + k, first + k + 1],
                "material": "aluminium",
                "section": "boom",
                "orientation": [0, 0, 1],
            }
            for k in range(4)
        ]
    tip = {"mass": "1 kg", "inertia": ["1e-3 kg*m**2"] * 3, "offset": ["0 m", "0 m", "50 mm"]}
    return {
        "nodes": nodes,
        "materials": {
            "aluminium": {"E": "70 GPa", "nu": 0.33, "density": "2700 kg/m**3"},
            "arm_steel": {"E": "200e9 Pa", "density": 0},
        },
        "sections": {
            "boom": {"shape": "rectangle", "width": "40 mm", "height": "2 cm"},
            "arm": {"shape": "tube", "outer_diameter": "0.1 m", "thickness": "10 mm"},
        },
        "elements": elements,
        "masses": [
            {"node": 0, "mass": "20 kg", "inertia": [f"{j} kg*m**2" for j in HUB_INERTIA]},
            {"node": 104, **tip},
            {"node": 204, **tip},
        ],
        "n_modes": 8,
        "damping": 0.005,
    }


def clamped_tube_fe() -> dict:
    return {
        "nodes": [{"id": k, "xyz": [f"{0.2 * k} m", 0, 0]} for k in range(11)],
        "materials": {"aluminium": {"E": "70 GPa", "nu": 0.33, "density": "2.7 g/cm**3"}},
        "sections": {"tube": {"shape": "tube", "outer_diameter": "30 mm", "thickness": "1 mm"}},
        "elements": [
            {"nodes": [k, k + 1], "material": "aluminium", "section": "tube"} for k in range(10)
        ],
        "masses": [{"node": 10, "mass": "500 g"}],
        "clamps": [{"node": 0, "dofs": "all"}],
        "n_modes": 6,
        "damping": 0.01,
    }


SPACECRAFT_PLANT = {"torque_node": 0, "displacements": [[104, "y"], [204, "z"]]}
STRUCTURE_PLANT = {
    "actuators": [{"name": "force", "node": 10, "axis": "z"}],
    "sensors": [{"name": "tip", "node": 10, "axis": "z"}],
}


def scenario(model: dict, plant: dict, **extra) -> str:
    document = {
        "kind": "simulation",
        "name": "own model",
        "model": model,
        "plant": plant,
        "simulation": {"duration": "0.5 s", "control_rate": "20 Hz"},
        "runs": [{"label": "free", "law": "open_loop"}],
        **extra,
    }
    return yaml.safe_dump(document, sort_keys=False)


def model_of(text: str, folder) -> ModalModel:
    return load_scenario(text).model.modal_model(folder)


def assert_same_modes(
    got: ModalModel, expected: ModalModel, rtol: float, shape_tol: float | None = None
) -> None:
    assert got.boundary == expected.boundary
    assert got.n_modes == expected.n_modes
    np.testing.assert_array_equal(got.node_ids, expected.node_ids)
    scale = expected.frequencies.max()
    np.testing.assert_allclose(got.frequencies, expected.frequencies, rtol=rtol, atol=rtol * scale)
    elastic = expected.frequencies > 0
    for g, e in zip(got.shapes[elastic], expected.shapes[elastic]):
        sign = np.sign(np.vdot(g, e))
        atol = (rtol if shape_tol is None else shape_tol) * np.abs(e).max()
        np.testing.assert_allclose(sign * g, e, rtol=0, atol=atol)


# -- acceptance ---------------------------------------------------------------------------------
STRUCTURES = {
    "hub_booms": (hub_booms_api, hub_booms_fe, SPACECRAFT_PLANT, FlexibleSpacecraft),
    "clamped_tube": (clamped_tube_api, clamped_tube_fe, STRUCTURE_PLANT, StructuralPlant),
}


@pytest.fixture(scope="module", params=list(STRUCTURES))
def structure(request):
    api, fe, plant, kind = STRUCTURES[request.param]
    return request.param, api(), fe, plant, kind


def test_inline_fe_equals_the_python_api(structure, tmp_path):
    _, expected, fe, plant, kind = structure
    got = model_of(scenario({"fe": fe()}, plant), tmp_path)
    assert_same_modes(got, expected, SAME_RTOL, SAME_SHAPE_TOL)
    np.testing.assert_allclose(got.rigid_mass, expected.rigid_mass, rtol=SAME_RTOL, atol=1e-12)
    assert isinstance(build_plant(load_scenario(scenario({"fe": fe()}, plant))), kind)


def test_netcdf_file_equals_the_python_api(structure, tmp_path):
    name, expected, _, plant, kind = structure
    expected.save(tmp_path / f"{name}.nc")
    (tmp_path / "run.yaml").write_text(scenario({"file": f"{name}.nc"}, plant))
    document = load_scenario(tmp_path / "run.yaml")  # the file is found beside the scenario
    assert_same_modes(document.model.modal_model(document.folder), expected, SAME_RTOL)
    np.testing.assert_array_equal(
        document.model.modal_model(document.folder).damping, expected.damping
    )
    assert isinstance(build_plant(document), kind)


def test_universal_file_equals_the_python_api(structure, tmp_path):
    name, expected, _, plant, kind = structure
    write_modal_uff(expected, tmp_path / f"{name}.uff")
    model: dict = {"file": f"{name}.uff"}
    if expected.boundary != "free":  # a universal file holds no mass properties
        model |= {
            "rigid_mass": expected.rigid_mass.tolist(),
            "participation": expected.participation.tolist(),
        }
    got = model_of(scenario(model, plant), tmp_path)
    assert_same_modes(got, expected, UFF_RTOL)
    np.testing.assert_allclose(got.damping, expected.damping, rtol=UFF_RTOL)
    text = scenario(model, plant)
    (tmp_path / "run.yaml").write_text(text)
    assert isinstance(build_plant(load_scenario(tmp_path / "run.yaml")), kind)


def test_the_clamped_tube_has_the_exact_tip_mass_cantilever_frequencies(tmp_path):
    """An independent check of the units on the way in: the YAML tube (mm, g/cm³, g) bends at
    the frequencies of the exact Euler-Bernoulli cantilever with a tip mass, to the
    discretisation error of 10 cubic elements (< 1e-4 on the first two bending pairs)."""
    got = model_of(scenario({"fe": clamped_tube_fe()}, STRUCTURE_PLANT), tmp_path)
    exact = TipMassCantilever(2.0, ALU.E * TUBE.Iz, ALU.rho * TUBE.A, 0.5, 0.0).modes(2).omegas
    bending = got.frequencies[[0, 1, 2, 3]]  # two planes, two modes each
    np.testing.assert_allclose(bending, np.repeat(exact, 2), rtol=1e-4)


def test_the_hub_booms_mass_properties(tmp_path):
    """The hub, two 2 m x 40 x 20 mm aluminium booms from 0.4 m to 2.4 m and two 1 kg tips
    (5 cm above the boom ends) by hand: the mass, and the inertia about z through the hub,
    J_hub + 2 ρA (2.4³ - 0.4³)/3 + 2 (1 kg (2.4 m)² + J_tip) (the arms are massless)."""
    got = model_of(scenario({"fe": hub_booms_fe()}, SPACECRAFT_PLANT), tmp_path)
    rho_a = 2700.0 * 0.04 * 0.02
    assert got.total_mass == pytest.approx(20.0 + 2 * rho_a * 2.0 + 2.0, rel=1e-12)
    expected = 0.7 + 2 * rho_a * (2.4**3 - 0.4**3) / 3 + 2 * (2.4**2 + 1e-3)
    assert got.rigid_mass[5, 5] == pytest.approx(expected, rel=1e-12)


def test_a_spacecraft_of_ones_own_slews(tmp_path):
    text = scenario(
        {"fe": hub_booms_fe()},
        SPACECRAFT_PLANT,
        initial={"euler123": ["0 deg", "0 deg", "0 deg"]},
    ).replace("law: open_loop", "law: mrp_pd")
    document = yaml.safe_load(text)
    document["runs"][0] |= {
        # the roll inertia is the hub's 0.6 kg m², pitch and yaw 32 kg m²
        "gains": {"K": "80 N*m", "P": ["4 N*m*s/rad", "40 N*m*s/rad", "40 N*m*s/rad"]},
        "target": {"euler123": [0, 0, "0.1 rad"]},
    }
    document["simulation"]["duration"] = "20 s"
    result = run_scenario(load_scenario(yaml.safe_dump(document)))
    row = result.metrics_records()[0]
    assert row["final_pointing_error_deg"] < 0.1 * 180 / np.pi / 10  # within a tenth
    assert row["peak_displacement_104Y"] > 0  # the booms bend as the hub turns about z
    assert result.dataset().attrs["case"] == "inline finite-element model"


def test_a_hub_with_appendages():
    model = {
        "hub_appendage": {
            "hub_inertia": "5 kg*m**2",
            "n_appendages": 2,
            "hub_radius": "0.3 m",
            "length": "2 m",
            "EI": "600 N*m**2",
            "rho": "0.3 kg/m",
            "tip_mass": "1 kg",
            "damping": 0.01,
        }
    }
    plant = build_plant(load_scenario(scenario(model, {"n_modes": 3})))
    expected = HubAppendage(
        HubAppendageParams(5.0, 2, 0.3, 2.0, 600.0, 0.3, 1.0, damping=0.01), n_modes=3
    )
    assert isinstance(plant, HubAppendage)
    np.testing.assert_array_equal(plant.frequencies(), expected.frequencies())


# -- refusals, each at its field path -----------------------------------------------------------
def _fe_with(change):
    fe = hub_booms_fe()
    change(fe)
    return {"fe": fe}


@pytest.mark.parametrize(
    "model, path, rule",
    [
        (
            _fe_with(lambda fe: fe["elements"][3].update(material="titanium")),
            "model.fe.elements[3].material",
            "unknown material 'titanium'",
        ),
        (
            _fe_with(lambda fe: fe["elements"][2].update(nodes=[101, 999])),
            "model.fe.elements[2].nodes",
            "unknown node 999",
        ),
        (
            _fe_with(lambda fe: fe["elements"][1].update(section="pipe")),
            "model.fe.elements[1].section",
            "unknown section 'pipe'",
        ),
        (
            _fe_with(lambda fe: fe["materials"]["aluminium"].update(E="-70 GPa")),
            "model.fe.materials.aluminium.E",
            "must be > 0",
        ),
        (
            _fe_with(lambda fe: fe["materials"]["aluminium"].update(E="70 kg")),
            "model.fe.materials.aluminium.E",
            "incompatible units",
        ),
        (
            _fe_with(lambda fe: fe["nodes"][2].update(xyz=["1 s", 0, 0])),
            "model.fe.nodes[2].xyz",
            "incompatible units",
        ),
        (
            _fe_with(lambda fe: fe["sections"]["boom"].update(Iy="1 m**4")),
            "model.fe.sections.boom.Iy",
            "not a dimension of a rectangle section",
        ),
        (
            _fe_with(lambda fe: fe["masses"][1].update(node=77)),
            "model.fe.masses[1].node",
            "unknown node 77",
        ),
        (
            _fe_with(lambda fe: fe["masses"][0].update(mass="-1 kg")),
            "model.fe.masses[0].mass",
            "must be >= 0",
        ),
        (
            _fe_with(lambda fe: fe["nodes"][3].update(id=0)),
            "model.fe.nodes[3]",
            "duplicate node id",
        ),
        ({"file": "missing.nc"}, "model.file", "no such file"),
        ({"file": "booms.stl"}, "model.file", "a model file ends in"),
        ({"file": "booms.nc", "op4": "booms.op4"}, "model.op4", "NASTRAN OP2 file only"),
        ({"fe": hub_booms_fe(), "file": "x.nc"}, "model", "exactly one of file"),
    ],
)
def test_bad_models_name_their_field(model, path, rule, tmp_path):
    with pytest.raises(ScenarioError) as info:
        document = load_scenario(scenario(model, SPACECRAFT_PLANT))
        build_plant(document)  # a file is read when the plant is built
    problems = info.value.problems
    assert any(p.path == path and rule in p.rule for p in problems), problems


def test_case_and_model_together_are_refused():
    text = scenario({"fe": hub_booms_fe()}, {}, case="eps")
    with pytest.raises(ScenarioError) as info:
        load_scenario(text)
    assert [p.path for p in info.value.problems] == ["model"]
    assert "exactly one of case" in info.value.problems[0].rule


def test_neither_case_nor_model_is_refused():
    document = yaml.safe_load(scenario({"fe": hub_booms_fe()}, {}))
    del document["model"]
    with pytest.raises(ScenarioError, match="case: give exactly one of case"):
        load_scenario(yaml.safe_dump(document))


@pytest.mark.parametrize(
    "plant, path, rule",
    [
        ({"actuators": []}, "plant.actuators", "does not apply to a free-free model"),
        ({"displacements": [[999, "y"]]}, "plant.displacements[0]", "unknown node 999"),
        ({"torque_node": 5}, "plant.torque_node", "unknown node 5"),
        ({"wobble": 1}, "plant.wobble", "not an option of a model's plant"),
    ],
)
def test_bad_plant_options_name_their_field(plant, path, rule):
    with pytest.raises(ScenarioError) as info:
        build_plant(load_scenario(scenario({"fe": hub_booms_fe()}, plant)))
    problems = info.value.problems
    assert any(p.path == path and rule in p.rule for p in problems), problems


def test_a_constrained_model_refuses_spacecraft_options(tmp_path):
    with pytest.raises(ScenarioError) as info:
        build_plant(load_scenario(scenario({"fe": clamped_tube_fe()}, SPACECRAFT_PLANT)))
    assert info.value.problems[0].path.startswith("plant.")
    assert "does not apply to a cantilevered model" in info.value.problems[0].rule


def test_the_model_is_not_mutated_by_loading():
    fe = hub_booms_fe()
    before = copy.deepcopy(fe)
    load_scenario(scenario({"fe": fe}, SPACECRAFT_PLANT))
    assert fe == before


# -- NASTRAN ------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def extseout():
    """pyyeti's NAS2CAM OP2/OP4 pair of an NX NASTRAN run (mm, kg, s; see
    tests/structures/test_io_nastran.py)."""
    pyyeti = pytest.importorskip("pyyeti", reason="the NASTRAN reader needs flexsat[nastran]")
    return Path(pyyeti.__file__).parent / "tests" / "nas2cam_extseout" / "nas2cam.op2"


def test_a_nastran_file_is_read_as_read_nastran_modes_reads_it(extseout):
    """The section passes the file, its units, the damping and the reference (given in SI in
    the scenario, in the model's mm to the reader) through unchanged."""
    from flexsat.structures import read_nastran_modes

    units = {"length": "mm", "mass": "kg", "time": "s"}
    model = {
        "file": str(extseout),
        "units": units,
        "damping": 0.01,
        "reference": ["0.6 m", 0, "300 mm"],
    }
    got = model_of(scenario(model, {}), extseout.parent)
    expected = read_nastran_modes(
        extseout, units=units, damping=0.01, reference=[600.0, 0.0, 300.0]
    )
    assert_same_modes(got, expected, SAME_RTOL)
    np.testing.assert_allclose(got.reference, [0.6, 0.0, 0.3], rtol=1e-15)
    np.testing.assert_allclose(got.rigid_mass, expected.rigid_mass, rtol=1e-14, atol=0)


def test_a_missing_op4_is_named(extseout, tmp_path):
    model = {"file": str(extseout), "op4": "nowhere.op4"}
    with pytest.raises(ScenarioError) as info:
        build_plant(load_scenario(scenario(model, {})))
    assert info.value.problems[0].path == "model.op4"
    assert "no such file" in info.value.problems[0].rule


def test_hub_appendage_damping_is_checked_against_the_modes():
    model = {
        "hub_appendage": {
            "hub_inertia": "5 kg*m**2",
            "n_appendages": 2,
            "hub_radius": "0.3 m",
            "length": "2 m",
            "EI": "600 N*m**2",
            "rho": "0.3 kg/m",
            "damping": [0.01, 0.02],
        }
    }
    with pytest.raises(ScenarioError) as info:
        build_plant(load_scenario(scenario(model, {"n_modes": 3})))
    assert info.value.problems[0].path == "model.hub_appendage.damping"
    assert "one per mode (3)" in info.value.problems[0].rule


def test_the_example_spacecraft_slews_and_settles():
    """examples/own_spacecraft_slew.yaml: the slew ends within 0.01° and settles in under
    15 s; the 2 m booms (offset from the hub wall) weigh 2 ρA L each, the tips 1 kg."""
    path = Path(__file__).resolve().parents[2] / "examples" / "own_spacecraft_slew.yaml"
    document = load_scenario(path)
    plant = build_plant(document)
    area = np.pi * (0.03**2 - 0.028**2) / 4
    assert plant.mass == pytest.approx(20.0 + 2 * 2700.0 * area * 2.0 + 2.0, rel=1e-12)
    row = run_scenario(document).metrics_records()[0]
    assert row["final_pointing_error_deg"] < 0.01
    assert row["pointing_settling_time_s"] < 15.0


def test_the_rigid_twin_has_the_flexible_spacecraft_inertia():
    """``rigid: true``: the inertia about the centre of mass, as the flexible plant carries it
    (hub, booms, tips by the parallel-axis theorem)."""
    from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft

    rigid = build_plant(load_scenario(scenario({"fe": hub_booms_fe()}, {"rigid": True})))
    flexible = build_plant(load_scenario(scenario({"fe": hub_booms_fe()}, SPACECRAFT_PLANT)))
    assert isinstance(rigid, RigidSpacecraft)
    np.testing.assert_allclose(rigid.inertia, flexible.inertia, rtol=0, atol=1e-12 * 32)
    with pytest.raises(ScenarioError, match="plant.n_modes: a rigid spacecraft has no modes"):
        build_plant(load_scenario(scenario({"fe": hub_booms_fe()}, {"rigid": True, "n_modes": 2})))


def test_a_thruster_on_a_rigid_bracket_of_the_hub(tmp_path):
    """A node tied rigidly to the hub node (rigid_links) carries a force actuator: its moment
    arm about the centre of mass is the bracket's position, and the force loads the modes
    through the hub's rigid motion (the dependent node's recovered shapes)."""
    fe = hub_booms_fe()
    fe["nodes"].append({"id": 300, "xyz": [0, "0.3 m", "0.1 m"]})
    fe["rigid_links"] = [{"node": 0, "nodes": [300]}]
    plant = build_plant(load_scenario(scenario({"fe": fe}, {"forces": [[300, "x"]]})))
    arm = np.array([0.0, 0.3, 0.1]) - plant.center_of_mass
    np.testing.assert_allclose(plant.force_moments[:, 0], np.cross(arm, [1.0, 0, 0]), atol=1e-15)
    # F e_x at r = (0, 0.3, 0.1) from the hub node: F e_x and the moment r x e_x = (0, 0.1, -0.3)
    modal = plant.modal
    hub = (
        modal.force_input(0, "x")
        + 0.1 * modal.torque_input(0, "y")
        - 0.3 * modal.torque_input(0, "z")
    )
    np.testing.assert_allclose(plant.force_modal[:, 0], hub, rtol=0, atol=1e-14)


# -- a plain SOL 103 OP2 -------------------------------------------------------------------------
#: the pyNastran-written fixtures of tests/structures/test_io_op2.py: float32 values, so each
#: value read back is flexsat's rounded to 2^-24 relative; 1e-6 bounds it with the eigen-solver's
#: round-off (λ_max/gap ~ 1e3 here)
OP2 = Path(__file__).resolve().parents[1] / "data" / "op2"
OP2_RTOL = 1e-6


def l_frame_fe(clamped: bool) -> dict:
    """The L-shaped frames of the OP2 fixtures (tests/data/op2/make_op2_fixtures.py) as an
    inline description: 1.2 m along x, then to (1.2, 0.7, 0.3) m, 30 x 50 then 30 x 20 mm
    aluminium, a 0.8 kg tip mass."""
    corner, tip = np.array([1.2, 0.0, 0.0]), np.array([1.2, 0.7, 0.3])
    points = [corner * t for t in np.linspace(0.0, 1.0, 5)]
    points += [corner + (tip - corner) * t for t in np.linspace(0.25, 1.0, 4)]
    fe = {
        "nodes": [
            {"id": 101 + i, "xyz": [f"{float(1000 * x)!r} mm" for x in p]}
            for i, p in enumerate(points)
        ],
        "materials": {"aluminium": {"E": "70 GPa", "nu": 0.33, "density": "2700 kg/m**3"}},
        "sections": {
            "deep": {"shape": "rectangle", "width": "30 mm", "height": "50 mm"},
            "flat": {"shape": "rectangle", "width": "30 mm", "height": "20 mm"},
        },
        "elements": [
            {"nodes": [101 + i, 102 + i], "material": "aluminium", "section": s}
            for i, s in enumerate(["deep"] * 4 + ["flat"] * 4)
        ],
        "masses": [{"node": 109, "mass": "0.8 kg", "inertia": [1e-3, 2e-3, 3e-3]}],
        "n_modes": 8,
    }
    if clamped:
        fe["clamps"] = [{"node": 101}]
    return fe


def test_a_plain_op2_of_the_free_frame_equals_its_inline_description(tmp_path):
    inline = model_of(scenario({"fe": l_frame_fe(False)}, {}), tmp_path)
    got = model_of(scenario({"file": str(OP2 / "free_frame.op2")}, {}), tmp_path)
    assert_same_modes(got, inline, OP2_RTOL)
    d = np.sqrt(np.diag(inline.rigid_mass))
    np.testing.assert_allclose(
        got.rigid_mass / np.outer(d, d), inline.rigid_mass / np.outer(d, d), atol=OP2_RTOL
    )


def test_a_plain_op2_of_the_clamped_frame_takes_its_participation(tmp_path):
    """A cantilevered OP2 has no rigid-body modes to derive the participation from: the section
    passes it (SI); the rigid mass is the file's OGPWG."""
    inline = model_of(scenario({"fe": l_frame_fe(True)}, STRUCTURE_PLANT), tmp_path)
    model = {"file": str(OP2 / "clamped_frame.op2"), "participation": inline.participation.tolist()}
    got = model_of(scenario(model, {}), tmp_path)
    assert_same_modes(got, inline, OP2_RTOL)
    d = np.sqrt(np.diag(inline.rigid_mass))
    np.testing.assert_allclose(
        got.rigid_mass / np.outer(d, d), inline.rigid_mass / np.outer(d, d), atol=OP2_RTOL
    )
    plant = {"actuators": [{"name": "f", "node": 109, "axis": "z"}]}
    assert isinstance(build_plant(load_scenario(scenario(model, plant))), StructuralPlant)
    with pytest.raises(ScenarioError) as info:
        build_plant(load_scenario(scenario({"file": str(OP2 / "clamped_frame.op2")}, plant)))
    assert info.value.problems[0].path == "model.file.participation"
    assert "cantilevered" in info.value.problems[0].rule
