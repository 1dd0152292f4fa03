"""Tests of flexsat.structures.io_uff.

pyuff ships no sample universal file (``pyuff/datasets`` holds only the dataset readers and
writers), and no other installed package has one, so every file here is written by pyuff's own
writer from ``pyuff.prepare_15/2411/55/58/164`` and read back through flexsat. The modal data
come from a free pin-jointed truss of point masses (translational dofs only, dense
``scipy.linalg.eigh``), whose rigid mass and participation Φᵀ M R are computed here directly;
one test goes through the NASTRAN model shipped with pyyeti (rotational dofs).

Tolerances: datasets 15 and 55 are written with six significant digits (``%13.5e``), so values
read back agree to 5e-6 relative; 1e-5 is used. Datasets 2411 and 164 are double precision, and
pyuff writes dataset 58 values with twelve digits (``%20.11e``): 1e-10.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg

from flexsat.structures.io_uff import (
    modal_model_from_uff,
    read_uff,
    read_uff_functions,
    write_modal_uff,
)
from flexsat.structures.modal_model import ModalModel

pyuff = pytest.importorskip(
    "pyuff", reason="optional dependency pyuff (flexsat[uff]) not installed"
)

TOL = 1e-5
XYZ = np.array(
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.2, 0.0], [0.0, 0.0, 0.8], [1.0, 1.0, 1.0]]
)
MASSES = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
NODE_IDS = np.array([10, 11, 12, 13, 14])


# ------------------------------------------------------------------------------------------------
# reference model and writers
def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _truss(fixed=()):
    """Free (or with ``fixed`` nodes removed) truss: ModalModel with exact mass properties."""
    n = len(XYZ)
    K = np.zeros((3 * n, 3 * n))
    for a in range(n):
        for b in range(a + 1, n):
            e = (XYZ[b] - XYZ[a]) / np.linalg.norm(XYZ[b] - XYZ[a])
            k = 1e3 * (1 + a + b) * np.outer(e, e)
            for i, j, sign in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                K[3 * i : 3 * i + 3, 3 * j : 3 * j + 3] += sign * k
    M = np.diag(np.repeat(MASSES, 3))
    R = np.vstack([np.hstack([np.eye(3), -_skew(r)]) for r in XYZ])
    keep = np.array([i // 3 not in fixed for i in range(3 * n)])
    lam, phi_free = scipy.linalg.eigh(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)])
    phi = np.zeros((3 * n, lam.size))
    phi[keep] = phi_free
    w = np.sqrt(np.clip(lam, 0.0, None))
    shapes = np.zeros((lam.size, n, 6))
    shapes[:, :, :3] = phi.T.reshape(lam.size, n, 3)
    return ModalModel(
        node_ids=NODE_IDS,
        coordinates=XYZ,
        frequencies=np.where(w < 1e-2, 0.0, w),
        damping=np.linspace(0.0, 0.02, lam.size),
        shapes=shapes,
        rigid_mass=R.T @ M @ R,
        participation=phi.T @ M @ R,
        boundary="cantilevered" if fixed else "free",
    )


@pytest.fixture(scope="module")
def free():
    return _truss()


def _write(path, datasets):
    pyuff.UFF(str(path)).write_sets(datasets, mode="overwrite")
    return path


def _nodes_15(xyz=XYZ, ids=NODE_IDS, **extra):
    return pyuff.prepare_15(
        node_nums=[int(i) for i in ids], x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2], **extra
    )


def _nodes_2411(xyz=XYZ, ids=NODE_IDS):
    n = len(ids)
    zeros = np.zeros(n, dtype=int)
    return pyuff.prepare_2411(
        node_nums=np.asarray(ids, dtype=int),
        def_cs=zeros,
        disp_cs=zeros,
        color=zeros,
        x=xyz[:, 0].copy(),
        y=xyz[:, 1].copy(),
        z=xyz[:, 2].copy(),
    )


def _mode_55(i, freq_hz, shape, modal_m=1.0, damping=0.0, ids=NODE_IDS):
    """One normal mode, 3 values per node (shape (n, 3))."""
    return pyuff.prepare_55(
        model_type=1,
        analysis_type=2,
        data_ch=2,
        spec_data_type=8,
        data_type=2,
        n_data_per_node=3,
        r1=shape[:, 0],
        r2=shape[:, 1],
        r3=shape[:, 2],
        node_nums=[int(n) for n in ids],
        load_case=1,
        mode_n=i,
        freq=float(freq_hz),
        modal_m=float(modal_m),
        modal_damp_vis=float(damping),
        modal_damp_his=0.0,
    )


def _modes_55(model, scale=None):
    """The model's modes as datasets 55, shapes times ``scale`` with modal mass scale²."""
    scale = np.ones(model.n_modes) if scale is None else scale
    return [
        _mode_55(i + 1, f, c * model.shapes[i, :, :3], c**2, model.damping[i])
        for i, (f, c) in enumerate(zip(model.frequencies_hz, scale))
    ]


def _function_58(node, direction, x, data, func_type=4, abscissa=18, **labels):
    return pyuff.prepare_58(
        func_type=func_type,
        rsp_node=node,
        rsp_dir=direction,
        ref_node=1,
        ref_dir=3,
        data=data,
        x=x,
        id1=f"H {node}:{direction}",
        rsp_ent_name="TEST",
        ref_ent_name="TEST",
        abscissa_spacing=1,
        abscissa_spec_data_type=abscissa,
        ordinate_spec_data_type=12,
        orddenom_spec_data_type=13,
        **labels,
    )


def _assert_models_close(got, expected):
    d = np.sqrt(np.diag(expected.rigid_mass))
    np.testing.assert_array_equal(got.node_ids, expected.node_ids)
    size = np.abs(expected.coordinates).max()
    np.testing.assert_allclose(got.coordinates, expected.coordinates, rtol=TOL, atol=TOL * size)
    np.testing.assert_allclose(got.frequencies, expected.frequencies, rtol=TOL)
    np.testing.assert_allclose(got.damping, expected.damping, rtol=TOL)
    tiny = 1e-12 * np.abs(expected.shapes).max()
    np.testing.assert_allclose(got.shapes, expected.shapes, rtol=TOL, atol=tiny)
    assert np.abs((got.rigid_mass - expected.rigid_mass) / np.outer(d, d)).max() < TOL
    assert np.abs((got.participation - expected.participation) / d).max() < TOL
    assert got.boundary == expected.boundary


# ------------------------------------------------------------------------------------------------
def test_read_uff_groups_datasets_by_type(tmp_path, free):
    f = np.linspace(0.0, 10.0, 11)
    path = _write(
        tmp_path / "all.uff",
        [
            pyuff.prepare_164(
                units_code=1,
                units_description="SI",
                temp_mode=1,
                length=1.0,
                force=1.0,
                temp=1.0,
                temp_offset=273.15,
            ),
            _nodes_15(),
            _nodes_2411(),
            *_modes_55(free)[:2],
            _function_58(10, 1, f, f + 1j * f),
        ],
    )
    sets = read_uff(path)
    assert {k: len(v) for k, v in sets.items()} == {164: 1, 15: 1, 2411: 1, 55: 2, 58: 1}
    np.testing.assert_allclose(sets[2411][0]["x"], XYZ[:, 0])
    assert sets[55][1]["mode_n"] == 2


def test_round_trip_free(tmp_path, free):
    path = tmp_path / "free.uff"
    write_modal_uff(free, path)
    assert {k: len(v) for k, v in read_uff(path).items()} == {164: 1, 15: 1, 55: free.n_modes}
    _assert_models_close(modal_model_from_uff(path), free)


def test_round_trip_about_another_reference(tmp_path, free):
    """Mass properties are derived about the reference given on reading."""
    write_modal_uff(free, tmp_path / "free.uff")
    got = modal_model_from_uff(tmp_path / "free.uff", reference=[1.0, 1.0, 1.0])
    np.testing.assert_allclose(got.center_of_mass, free.center_of_mass, rtol=TOL)
    size = np.abs(free.inertia()).max()
    np.testing.assert_allclose(got.inertia(), free.inertia(), rtol=TOL, atol=TOL * size)


def test_round_trip_cantilevered_needs_mass_properties(tmp_path):
    model = _truss(fixed=(0, 1, 2))  # three pinned nodes: no rigid-body mode
    path = tmp_path / "cantilever.uff"
    write_modal_uff(model, path)
    with pytest.raises(ValueError, match="found 0: pass rigid_mass= and participation="):
        modal_model_from_uff(path)
    got = modal_model_from_uff(path, rigid_mass=model.rigid_mass, participation=model.participation)
    _assert_models_close(got, model)


def test_round_trip_with_rotations(tmp_path):
    """The NASTRAN model shipped with pyyeti (6 dofs per grid; mm, kg, s) -> UFF -> model."""
    pyyeti = pytest.importorskip("pyyeti", reason="optional dependency pyyeti (flexsat[nastran])")
    from flexsat.structures.io_nastran import read_nastran_modes

    op2 = Path(pyyeti.__file__).parent / "tests" / "nas2cam_extseout" / "nas2cam.op2"
    mm_kg_s = {"length": "mm", "mass": "kg", "time": "s"}
    model = read_nastran_modes(op2, reference=[600.0, 0.0, 300.0], units=mm_kg_s)
    write_modal_uff(model, tmp_path / "nastran.uff")
    _assert_models_close(
        modal_model_from_uff(tmp_path / "nastran.uff", reference=model.reference), model
    )


def test_modal_mass_normalisation_and_file_damping(tmp_path, free):
    scale = np.linspace(0.5, 3.0, free.n_modes)
    path = _write(tmp_path / "scaled.uff", [_nodes_15(), *_modes_55(free, scale)])
    got = modal_model_from_uff(path)
    _assert_models_close(got, free)
    as_is = modal_model_from_uff(
        path,
        normalisation="as_is",
        damping=0.01,
        rigid_mass=free.rigid_mass,
        participation=free.participation,
    )
    np.testing.assert_allclose(
        as_is.shapes, free.shapes * scale[:, None, None], rtol=TOL, atol=1e-12
    )
    np.testing.assert_array_equal(as_is.damping, 0.01)


def test_nodes_from_2411_in_full_precision(tmp_path, free):
    xyz = XYZ + 1e-9
    path = _write(tmp_path / "2411.uff", [_nodes_2411(xyz), *_modes_55(free)])
    np.testing.assert_allclose(modal_model_from_uff(path).coordinates, xyz, rtol=1e-15)


def test_units_dataset_164(tmp_path, free):
    """Inch, pound-force file (164 code 7): one file mass unit is f_L / f_F = 175.127 kg."""
    f_length, f_force = 1 / 0.0254, 1 / 4.4482216152605
    mass_unit = f_length / f_force
    s = np.sqrt(mass_unit) * np.array([1, 1, 1, 0.0254, 0.0254, 0.0254])
    file_model = [
        _mode_55(i + 1, free.frequencies_hz[i], free.shapes[i, :, :3] * s[:3], 1.0, free.damping[i])
        for i in range(free.n_modes)
    ]
    path = _write(
        tmp_path / "inch.uff",
        [
            pyuff.prepare_164(
                units_code=7,
                units_description="IN",
                temp_mode=1,
                length=f_length,
                force=f_force,
                temp=1.8,
                temp_offset=459.67,
            ),
            _nodes_2411(XYZ * f_length),
            *file_model,
        ],
    )
    assert mass_unit == pytest.approx(175.126835, rel=1e-8)
    _assert_models_close(modal_model_from_uff(path), free)


def test_functions_58(tmp_path):
    f = np.linspace(0.0, 50.0, 101)
    h1, h2 = 1.0 / (1.0 + 1j * f), 2.0 / (3.0 - f**2 + 1j * f)
    labels = dict(
        ordinate_axis_units_lab="m/s^2", orddenom_axis_units_lab="N", abscissa_axis_units_lab="Hz"
    )
    path = _write(
        tmp_path / "frf.uff",
        [
            _function_58(10, 3, f, h1, **labels),
            _function_58(11, -2, f, h2, **labels),
        ],
    )
    ds = read_uff_functions(path)
    assert ds["data"].dims == ("function", "frequency")
    np.testing.assert_allclose(ds["frequency"], f)
    assert ds["frequency"].attrs["units"] == "Hz"
    np.testing.assert_allclose(ds["data"].values, np.stack([h1, h2]), rtol=1e-10)
    assert list(ds["response_node"].values) == [10, 11]
    assert list(ds["response_direction"].values) == [3, -2]
    assert list(ds["reference_node"].values) == [1, 1]
    assert list(ds["function_type"].values) == [4, 4]
    assert list(ds["ordinate_units"].values) == ["m/s^2", "m/s^2"]
    assert list(ds["denominator_units"].values) == ["N", "N"]
    assert list(ds["description"].values) == ["H 10:3", "H 11:-2"]


def test_time_response_58(tmp_path):
    t = np.linspace(0.0, 1.0, 64)
    path = _write(
        tmp_path / "time.uff", [_function_58(12, 1, t, np.sin(5 * t), func_type=1, abscissa=17)]
    )
    ds = read_uff_functions(path)
    assert ds["data"].dims == ("function", "time")
    assert ds["data"].dtype == float
    np.testing.assert_allclose(ds["data"].values[0], np.sin(5 * t), rtol=1e-10)
    assert ds["time"].attrs["units"] == "" and ds["ordinate_units"].values[0] == ""


# ------------------------------------------------------------------------------------------------
# bad input
@pytest.mark.parametrize("reader", [read_uff, modal_model_from_uff, read_uff_functions])
def test_missing_file(tmp_path, reader):
    with pytest.raises(FileNotFoundError, match="universal file not found") as info:
        reader(tmp_path / "absent.uff")
    assert str(tmp_path / "absent.uff") in str(info.value)


def test_not_a_universal_file(tmp_path):
    path = tmp_path / "text.uff"
    path.write_text("hello\n")
    with pytest.raises(ValueError, match="no universal-file datasets"):
        read_uff(path)


def test_file_without_modal_data(tmp_path):
    path = _write(tmp_path / "nodes.uff", [_nodes_15()])
    with pytest.raises(ValueError, match=r"no modal data \(dataset 55 with analysis type 2"):
        modal_model_from_uff(path)
    with pytest.raises(ValueError, match=r"no function data \(dataset 58\)"):
        read_uff_functions(path)


def test_file_without_nodes(tmp_path, free):
    path = _write(tmp_path / "modes.uff", _modes_55(free))
    with pytest.raises(ValueError, match=r"no node coordinates \(dataset 15 or 2411\)"):
        modal_model_from_uff(path)


def test_unknown_modal_mass(tmp_path, free):
    path = _write(tmp_path / "nomass.uff", [_nodes_15(), *_modes_55(free, np.zeros(free.n_modes))])
    with pytest.raises(ValueError, match="mode 1 has no modal mass .* normalisation='as_is'"):
        modal_model_from_uff(path)
    with pytest.raises(ValueError, match="normalisation: must be one of"):
        modal_model_from_uff(path, normalisation="unit")


def test_local_coordinate_systems_refused(tmp_path, free):
    path = _write(tmp_path / "local.uff", [_nodes_15(def_cs=[0, 0, 1, 0, 0]), *_modes_55(free)])
    with pytest.raises(ValueError, match="local coordinate systems"):
        modal_model_from_uff(path)


def test_values_at_unknown_nodes(tmp_path, free):
    path = _write(tmp_path / "extra.uff", [_nodes_15(XYZ[:4], NODE_IDS[:4]), *_modes_55(free)])
    with pytest.raises(ValueError, match=r"mode 1 has values at nodes \[14\] without coordinates"):
        modal_model_from_uff(path)


def test_rigid_modes_that_are_not_rigid(tmp_path, free):
    bent = free.shapes[:, :, :3].copy()
    bent[0, 0] += 0.5
    modes = [_mode_55(i + 1, free.frequencies_hz[i], bent[i]) for i in range(free.n_modes)]
    path = _write(tmp_path / "bent.uff", [_nodes_15(), *modes])
    with pytest.raises(ValueError, match="rigid-body modes do not span the rigid motions"):
        modal_model_from_uff(path)


def test_one_mass_property_alone(tmp_path, free):
    write_modal_uff(free, tmp_path / "free.uff")
    with pytest.raises(ValueError, match="rigid_mass, participation: give both or neither"):
        modal_model_from_uff(tmp_path / "free.uff", rigid_mass=free.rigid_mass)


def test_different_abscissae(tmp_path):
    f = np.linspace(0.0, 10.0, 11)
    path = _write(
        tmp_path / "mixed.uff", [_function_58(10, 1, f, f), _function_58(11, 1, f[:5], f[:5])]
    )
    with pytest.raises(ValueError, match="functions 1 and 2 have different abscissae"):
        read_uff_functions(path)


@pytest.mark.parametrize(
    "call",
    [
        lambda p: read_uff(p),
        lambda p: modal_model_from_uff(p),
        lambda p: read_uff_functions(p),
        lambda p: write_modal_uff(None, p),
    ],
)
def test_missing_pyuff_is_explained(monkeypatch, tmp_path, call):
    monkeypatch.setitem(sys.modules, "pyuff", None)
    message = r"needs the optional dependency pyuff: pip install 'flexsat\[uff\]'"
    with pytest.raises(ImportError, match=message):
        call(tmp_path / "any.uff")
