"""Tests of flexsat.structures.io_nastran on the NASTRAN files shipped with pyyeti.

Files (in ``pyyeti/tests``):

* ``nas2cam_extseout/nas2cam.op2/.op4`` (NX NASTRAN SEMFREQ run, ``assemble.dat``): residual
  superelement 0 with grids 3, 11, 19, 27, 70 (11 and 70 output in rectangular system 10),
  the modal spoints of two upstream superelements, MAA, KAA, LAMBDA, PHG; free, 54 modes.
  Units mm, kg, s (MAT1 E = 6.894e7 kg/(mm s²), ρ = 2.74e-6 kg/mm³ in ``inboard.blk``).
  ``assemble.out`` holds NASTRAN's own eigenvalue table and G-set weight check, used below as
  independent references (printed to 7 digits -> tolerance 1e-6).
* ``nas2cam_csuper/nas2cam``: its NASTRAN weight check (``assemble.out``, p. "M O") shows a
  direction-dependent translational mass, which ModalModel must refuse.
* ``nas2cam/no_se_nas2cam`` (LAMBDA only) and ``nas2cam/bigend_nas2cam`` (no modal data).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from flexsat.structures.io_nastran import read_nastran_modes
from flexsat.units import UnitError

MM_KG_S = {"length": "mm", "mass": "kg", "time": "s"}
NO_PYYETI = "optional dependency pyyeti (flexsat[nastran]) not installed"

# assemble.out, "O U T P U T   F R O M   W E I G H T   C H E C K", G set, reference point 0
# (basic origin), units kg, kg mm, kg mm².
NASTRAN_MO = np.array(
    [
        [3.345436e00, 1.598721e-13, -1.132427e-12, -1.873559e-10, 5.018153e02, -5.018153e02],
        [1.622036e-13, 3.345436e00, -1.922240e-12, -5.018153e02, 2.731554e-09, 2.118899e03],
        [-1.133316e-12, -1.928013e-12, 3.345436e00, 5.018153e02, -2.118899e03, -1.996398e-09],
        [-1.874909e-10, -5.018153e02, 5.018153e02, 5.433826e05, -3.178349e05, -3.178349e05],
        [5.018153e02, 2.734168e-09, -2.118899e03, -3.178349e05, 2.441110e06, -7.527230e04],
        [-5.018153e02, 2.118899e03, -1.992703e-09, -3.178349e05, -7.527230e04, 2.772279e06],
    ]
)
# assemble.out, "R E A L   E I G E N V A L U E S", modes 7-12 (rad/s)².
NASTRAN_EIGENVALUES = np.array(
    [1.139316e02, 1.233310e02, 1.362450e02, 4.616507e02, 1.947847e03, 1.948512e03]
)


@pytest.fixture(scope="module")
def pyyeti_tests() -> Path:
    pyyeti = pytest.importorskip("pyyeti", reason=NO_PYYETI)
    return Path(pyyeti.__file__).parent / "tests"


@pytest.fixture(scope="module")
def extseout(pyyeti_tests) -> Path:
    return pyyeti_tests / "nas2cam_extseout" / "nas2cam.op2"


@pytest.fixture(scope="module")
def nas(extseout):
    from pyyeti.nastran import op2

    return op2.rdnas2cam(str(extseout))


@pytest.fixture(scope="module")
def model(extseout):
    return read_nastran_modes(extseout, units=MM_KG_S)


def _scaled(a, d):
    return a / np.outer(d, d)


def _rigid_vectors(coordinates, reference=None):
    """(n, 6, 6) rigid-body motion of each node: u = t + θ × r, rotation θ (about ``reference``,
    default the origin)."""
    reference = np.zeros(3) if reference is None else reference
    out = np.zeros((len(coordinates), 6, 6))
    for i, r in enumerate(coordinates - reference):
        out[i, :3, :3] = out[i, 3:, 3:] = np.eye(3)
        out[i, :3, 3:] = -np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
    return out


# ------------------------------------------------------------------------------------------------
def test_pyyeti_data_are_mass_normalised(nas):
    """Φᵀ M Φ = I on the a-set: the shapes read are the mass-normalised ones (measured 1.3e-13)."""
    from pyyeti.nastran import n2p

    aset = n2p.mksetpv(nas["uset"][0], "g", "a")
    pha = nas["phg"][0][aset]
    assert np.abs(pha.T @ nas["maa"][0] @ pha - np.eye(pha.shape[1])).max() < 1e-6


def test_frequencies_are_pyyeti_lambda(model, nas):
    lam = nas["lambda"][0]
    assert model.n_modes == lam.size == 54
    assert nas["nrb"] == 6 and np.all(model.frequencies[:6] == 0.0)
    np.testing.assert_allclose(model.frequencies[6:] ** 2, lam[6:], rtol=1e-12)
    np.testing.assert_allclose(model.frequencies[6:12] ** 2, NASTRAN_EIGENVALUES, rtol=1e-6)
    assert model.boundary == "free"


def test_rigid_mass_matches_nastran_weight_check(model):
    """Rᵀ M_aa R from the Craig–Bampton residual equals NASTRAN's G-set weight check."""
    s = np.array([1, 1, 1, 1e-3, 1e-3, 1e-3])  # kg, kg m, kg m² from kg, kg mm, kg mm²
    expected = NASTRAN_MO * np.outer(s, s)
    d = np.sqrt(np.diag(expected))
    assert np.abs(_scaled(model.rigid_mass - expected, d)).max() < 1e-6
    trans = model.rigid_mass[:3, :3]
    assert model.total_mass == pytest.approx(np.trace(trans) / 3, rel=1e-9)
    assert model.total_mass == pytest.approx(3.345436, rel=1e-6)


def test_participation_is_complete(model, nas):
    """54 modes on a 54-dof a-set are complete: Lᵀ L = M_rr (Bessel with equality)."""
    L = model.participation
    d = np.sqrt(np.diag(model.rigid_mass))
    assert np.abs(_scaled(L.T @ L - model.rigid_mass, d)).max() < 1e-6
    # flexible modes of a free body carry no momentum
    assert np.abs(L[6:] / d).max() < 1e-6


def test_shapes_in_basic(model, nas):
    """Shapes are T phg per grid, T the output-to-basic rotation printed in the USET table."""
    uset, phg = nas["uset"][0], nas["phg"][0]
    assert list(model.node_ids) == [70, 3, 11, 19, 27]
    np.testing.assert_allclose(model.coordinates[2], [0.6, 0.3, 0.3])
    for j, gid in enumerate(model.node_ids):
        row = uset.index.get_loc((gid, 1))
        T = uset.iloc[row + 3 : row + 6][["x", "y", "z"]].to_numpy()
        local = phg[row : row + 6] / np.array([1, 1, 1, 1e-3, 1e-3, 1e-3])[:, None]
        np.testing.assert_allclose(
            model.shapes[:, j, :3], (T @ local[:3]).T, rtol=1e-12, atol=1e-14
        )
        np.testing.assert_allclose(
            model.shapes[:, j, 3:], (T @ local[3:]).T, rtol=1e-12, atol=1e-14
        )


def test_rigid_modes_move_rigidly_in_basic(model):
    """The six rigid-body shapes at the a-set grids (3, 11 in system 10, 19, 27) are a rigid
    motion in basic: least-squares residual < 1e-8 of the shapes."""
    nodes = [1, 2, 3, 4]
    R = _rigid_vectors(model.coordinates[nodes]).reshape(-1, 6)
    phi = model.shapes[:6, nodes, :].reshape(6, -1).T
    A, *_ = np.linalg.lstsq(R, phi, rcond=None)
    assert np.linalg.norm(R @ A - phi) < 1e-8 * np.linalg.norm(phi)


def test_units_convert_with_pint(extseout, model):
    si = read_nastran_modes(extseout)  # numbers taken as SI
    s = np.array([1, 1, 1, 1e-3, 1e-3, 1e-3])
    np.testing.assert_allclose(model.coordinates, si.coordinates * 1e-3)
    np.testing.assert_allclose(model.frequencies, si.frequencies)
    np.testing.assert_allclose(model.shapes, si.shapes / s, rtol=1e-12)
    np.testing.assert_allclose(model.rigid_mass, si.rigid_mass * np.outer(s, s), rtol=1e-12)
    np.testing.assert_allclose(model.participation, si.participation * s, rtol=1e-12)
    tonne = read_nastran_modes(
        extseout, units={"length": "mm", "mass": "t", "time": "ms"}, rigid_frequency=1.0
    )
    assert tonne.total_mass == pytest.approx(1e3 * model.total_mass, rel=1e-12)
    np.testing.assert_allclose(tonne.frequencies, 1e3 * model.frequencies, rtol=1e-12)


def test_rigid_frequency_too_low_for_the_time_unit(extseout):
    """In ms the rigid modes' roundoff is 0.07-0.19 rad/s, above the default 0.01 rad/s."""
    with pytest.raises(ValueError, match="rigid_frequency: eigenvalues are not ascending"):
        read_nastran_modes(extseout, units={"length": "mm", "mass": "kg", "time": "ms"})


def test_reference_point(extseout, model):
    """About grid 3 ([600, 0, 300] mm): same centre of mass, parallel-axis inertia."""
    at3 = read_nastran_modes(extseout, reference=[600.0, 0.0, 300.0], units=MM_KG_S)
    np.testing.assert_allclose(at3.reference, [0.6, 0.0, 0.3])
    np.testing.assert_allclose(at3.center_of_mass, model.center_of_mass, rtol=1e-10)
    inertia = model.inertia(about=[0.6, 0.0, 0.3])
    np.testing.assert_allclose(at3.rigid_mass[3:, 3:], inertia, atol=1e-10 * np.abs(inertia).max())


def test_damping_is_passed_on(extseout):
    zeta = np.linspace(0.0, 0.05, 54)
    np.testing.assert_array_equal(read_nastran_modes(extseout, damping=zeta).damping, zeta)


def test_g_set_mass(extseout, model, monkeypatch):
    """With MGG instead of MAA (here MAA scattered into the g-set) the result is the same."""
    from pyyeti.nastran import n2p, op2

    original = op2.rdnas2cam

    def with_mgg(*args):
        nas = original(*args)
        aset = n2p.mksetpv(nas["uset"][0], "g", "a")
        mgg = np.zeros((aset.size, aset.size))
        mgg[np.ix_(aset, aset)] = nas.pop("maa")[0]
        nas["mgg"] = {0: mgg}
        return nas

    monkeypatch.setattr(op2, "rdnas2cam", with_mgg)
    gset = read_nastran_modes(extseout, units=MM_KG_S)
    np.testing.assert_allclose(gset.rigid_mass, model.rigid_mass, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(gset.participation, model.participation, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("dropped, boundary", [(6, "cantilevered"), (3, None)])
def test_boundary_from_rigid_mode_count(extseout, monkeypatch, dropped, boundary):
    from pyyeti.nastran import op2

    original = op2.rdnas2cam

    def without_rigid(*args):
        nas = original(*args)
        nas["lambda"][0] = nas["lambda"][0][dropped:]
        nas["phg"][0] = nas["phg"][0][:, dropped:]
        return nas

    monkeypatch.setattr(op2, "rdnas2cam", without_rigid)
    if boundary is None:
        with pytest.raises(ValueError, match="3 rigid-body modes for 6 rigid motions"):
            read_nastran_modes(extseout)
    else:
        assert read_nastran_modes(extseout).boundary == boundary


# ------------------------------------------------------------------------------------------------
# bad input
def test_missing_files(tmp_path, extseout):
    missing = tmp_path / "model.op2"
    with pytest.raises(FileNotFoundError, match="OP2 file not found") as info:
        read_nastran_modes(missing)
    assert str(missing) in str(info.value)
    with pytest.raises(FileNotFoundError, match="OP4 file not found") as info:
        read_nastran_modes(extseout, op4_path=tmp_path / "other.op4")
    assert str(tmp_path / "other.op4") in str(info.value)


@pytest.mark.parametrize(
    "name, missing",
    [
        ("no_se_nas2cam", "missing g-set mode shapes PHG, mass matrix MAA or MGG"),
        (
            "bigend_nas2cam",
            "missing eigenvalues LAMBDA, g-set mode shapes PHG, mass matrix MAA or MGG",
        ),
    ],
)
def test_file_without_modal_data(pyyeti_tests, name, missing):
    message = f"{name}.op2/{name}.op4: no modal data for superelement 0: {missing}"
    with pytest.raises(ValueError, match=message):
        read_nastran_modes(pyyeti_tests / "nas2cam" / f"{name}.op2")


def test_unknown_superelement(extseout):
    message = r"superelement: 7 is not in nas2cam.op2/nas2cam.op4 \(superelements \[0, 101, 102\]\)"
    with pytest.raises(ValueError, match=message):
        read_nastran_modes(extseout, superelement=7)


def test_upstream_superelement_without_shapes(extseout):
    message = "superelement 101: missing eigenvalues LAMBDA, g-set mode shapes PHG"
    with pytest.raises(ValueError, match=message):
        read_nastran_modes(extseout, superelement=101)


def test_inconsistent_nastran_mass_is_refused(pyyeti_tests):
    """NASTRAN's own weight check of this model prints translational masses 5.29, 5.91, 4.29."""
    with pytest.raises(ValueError, match="rigid_mass: translational block must be m·I"):
        read_nastran_modes(pyyeti_tests / "nas2cam_csuper" / "nas2cam.op2")


@pytest.mark.parametrize(
    "units, error, match",
    [
        (
            {"length": "kg", "mass": "kg", "time": "s"},
            UnitError,
            r"units\['length'\]: incompatible units",
        ),
        (
            {"length": "mm", "mass": "kg"},
            ValueError,
            "units: must map exactly 'length', 'mass' and 'time'",
        ),
        (
            {"length": "mm", "mass": "furlong_per_ounce", "time": "s"},
            UnitError,
            r"units\['mass'\]: cannot read",
        ),
    ],
)
def test_bad_units(extseout, units, error, match):
    with pytest.raises(error, match=match):
        read_nastran_modes(extseout, units=units)


def test_bad_reference(extseout):
    with pytest.raises(ValueError, match=r"reference: must have shape \(3,\)"):
        read_nastran_modes(extseout, reference=[0.0, 0.0])


def test_missing_pyyeti_is_explained(monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "pyyeti", None)
    monkeypatch.setitem(sys.modules, "pyyeti.nastran", None)
    for suffix in (".op2", ".op4"):  # a NAS2CAM pair: without the OP4 no pyyeti is needed
        (tmp_path / f"any{suffix}").write_bytes(b"")
    with pytest.raises(ImportError, match=r"pip install 'flexsat\[nastran\]'"):
        read_nastran_modes(tmp_path / "any.op2")


def test_reading_a_model_leaves_numpy_printing_alone(extseout):
    """pyyeti's nastran.n2p sets numpy's legacy print options when first imported; reading a
    model must not change how the user's arrays print (a fresh interpreter, the first import)."""
    import subprocess
    import sys

    code = (
        "import numpy as np\n"
        "from flexsat.structures.io_nastran import read_nastran_modes\n"
        f"read_nastran_modes({str(extseout)!r}, units={MM_KG_S!r})\n"
        "print(np.get_printoptions()['legacy'], np.array([4.54, 4.3]))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    ).stdout
    assert out.strip() == "False [4.54 4.3 ]"
