"""Tests of flexsat.structures.io_op2, the plain SOL 103 OP2 reader.

No NASTRAN here, so two encoders stand in for it:

* ``tests/data/op2/free_frame.op2`` and ``clamped_frame.op2`` were written by pyNastran 1.4.1's
  OP2 writer (a throwaway numpy < 2 venv; ``tests/data/op2/make_op2_fixtures.py``) from the
  modes flexsat computes for the L-shaped frames built again below by :func:`_frame`: GEOM1 GRID
  records, LAMA, OUGV1 and, for the clamped frame, OGPWG with the frame's R^T M R. pyNastran
  writes 32-bit little-endian words and stores reals in single precision, so every value read
  back is the flexsat value rounded to float32: relative error <= 2^-24 element by element.
* :class:`_Encoder` writes the same tables from the format description (DMAP Programmer's
  Guide, see the module under test) in 64-bit words and either byte order, and the broken or
  foreign files that the refusals need.

The frames are rebuilt here, not loaded: the fixtures must agree with flexsat's own modes. An
eigenvector's sign is arbitrary (another BLAS may flip it), so shapes are compared after
aligning each mode's sign.
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np
import pytest

from flexsat.input_checks import FieldError
from flexsat.structures import (
    Material,
    Section,
    Structure,
    read_nastran_modes,
    read_op2,
    read_op2_modes,
)

DATA = Path(__file__).resolve().parents[1] / "data" / "op2"
F32 = 2.0**-24  # relative rounding of a float32
# a rigid mass derived from float32 shapes by least squares: a few roundings, ~1e-7 measured
DERIVED = 1e-6


def _frame(clamped: bool):
    """The frames of make_op2_fixtures.py: L-shaped, rectangular aluminium members, tip mass."""
    alu = Material(E=70e9, rho=2700.0, nu=0.33)
    s = Structure("op2 fixture")
    corner, tip = np.array([1.2, 0.0, 0.0]), np.array([1.2, 0.7, 0.3])
    points = [corner * t for t in np.linspace(0.0, 1.0, 5)]
    points += [corner + (tip - corner) * t for t in np.linspace(0.25, 1.0, 4)]
    for i, xyz in enumerate(points):
        s.add_node(101 + i, xyz)
    for i in range(len(points) - 1):
        s.add_frame(101 + i, 102 + i, alu, Section.rectangle(0.03, 0.05 if i < 4 else 0.02))
    s.add_mass(101 + len(points) - 1, 0.8, inertia=[1e-3, 2e-3, 3e-3])
    if clamped:
        s.clamp(101)
        return s, s.assemble().modes(8)
    return s, s.assemble().modes(14, rigid_body_modes=6)


@pytest.fixture(scope="module")
def free():
    return _frame(False)


@pytest.fixture(scope="module")
def clamped():
    return _frame(True)


def _rigid_mass(reference=(0.0, 0.0, 0.0)):
    """R^T M R of the whole frame (supports included) about ``reference``."""
    a = _frame(False)[1].assembly
    R = a.rigid_body_vectors(reference)
    return R.T @ (a.M @ R)


def _participation(fe, reference=(0.0, 0.0, 0.0)):
    R = fe.assembly.rigid_body_vectors(reference)
    return fe.shapes.T @ (fe.assembly.M @ R)


def _aligned(got, expected):
    """``got`` with each mode's sign flipped to match ``expected`` (m, n, 6)."""
    signs = np.sign(np.einsum("mij,mij->m", got, expected))
    return got * signs[:, None, None]


def _scaled_error(a, b, rigid_mass):
    d = np.sqrt(np.diag(rigid_mass))
    return np.abs((a - b) / np.outer(d, d)).max()


# ------------------------------------------------------------------------------------------------
# a small OP2 encoder written from the format description
class _Encoder:
    def __init__(self, word: int = 4, endian: str = "<") -> None:
        self.word, self.endian = word, endian

    def i(self, *values: int) -> bytes:
        return np.array(values, f"{self.endian}i{self.word}").tobytes()

    def f(self, *values: float) -> bytes:
        return np.array(values, f"{self.endian}f{self.word}").tobytes()

    def text(self, s: str, words: int) -> bytes:
        return s.encode().ljust(words * self.word)

    def record(self, payload: bytes) -> bytes:
        n = struct.pack(f"{self.endian}i", len(payload))
        return n + payload + n

    def marker(self, *values: int) -> bytes:
        return b"".join(self.record(self.i(v)) for v in values)

    def header(self) -> bytes:
        return (
            self.marker(3)
            + self.record(self.i(12, 7, 26))
            + self.marker(7)
            + self.record(self.text("NASTRAN FORT TAPE ID CODE - ", 7))
            + self.marker(2)
            + self.record(self.text("XXXXXXXX", 2))
            + self.marker(-1, 0)
        )

    def table(self, name: str, records: list[bytes]) -> bytes:
        out = self.marker(2) + self.record(self.text(name, 2))
        out += self.marker(-1, 7) + self.record(self.i(101, 0, 0, 0, 0, 0, 0))
        for k, payload in enumerate([self.text(name, 2), *records]):
            out += self.marker(-2 - k, 1, 0, len(payload) // self.word) + self.record(payload)
        return out + self.marker(-2 - len(records) - 1, 1, 0, 0)

    def ident(self, *head: int | float) -> bytes:
        """146-word IDENT: ints, reals where a float is given, zeros to the end."""
        words = [self.f(v) if isinstance(v, float) else self.i(v) for v in head]
        return b"".join(words) + self.i(*([0] * (146 - len(head))))

    def geom1(self, ids, xyz, cp=None, cd=None) -> bytes:
        cp = np.zeros(len(ids), int) if cp is None else cp
        cd = np.zeros(len(ids), int) if cd is None else cd
        grids = b"".join(
            self.i(int(n), int(p)) + self.f(*x) + self.i(int(d), 0, 0)
            for n, p, x, d in zip(ids, cp, xyz, cd)
        )
        return self.table("GEOM1", [self.i(4501, 45, 1) + grids, self.i(65535, 65535, 65535)])

    def lama(self, lam, generalized_mass=None) -> bytes:
        mu = np.ones(len(lam)) if generalized_mass is None else generalized_mass
        w = np.sqrt(np.clip(lam, 0.0, None))
        rows = b"".join(
            self.i(k + 1, k + 1) + self.f(x, om, om / (2 * np.pi), m, x * m)
            for k, (x, om, m) in enumerate(zip(lam, w, mu))
        )
        return self.table("LAMA", [self.ident(21, 21), rows])

    def oug(self, name, ids, lam, shapes, acode=22, tcode=7, fmt=1, width=8, subcases=None):
        records = []
        for k, (x, shape) in enumerate(zip(lam, shapes)):
            subcase = 1 if subcases is None else subcases[k]
            records.append(
                self.ident(acode, tcode, 0, subcase, k + 1, float(x), 0.0, 0, fmt, width)
            )
            records.append(
                b"".join(self.i(10 * int(n) + 2, 1) + self.f(*v) for n, v in zip(ids, shape))
            )
        return self.table(name, records)

    def ogpwg(self, rigid_mass, point=0) -> bytes:
        return self.table(
            "OGPWG", [self.ident(1, 13, point), self.f(*rigid_mass.ravel(), *np.zeros(42))]
        )

    def modes(self, s, fe, table="OUGV1", rigid_mass=None, **oug) -> bytes:
        """A whole SOL 103 OP2 of a flexsat frame."""
        lam = fe.omegas**2
        out = self.header() + self.geom1(s.node_ids, s.coordinates) + self.lama(lam)
        if rigid_mass is not None:
            out += self.ogpwg(rigid_mass)
        return out + self.oug(table, s.node_ids, lam, fe.at_nodes(), **oug) + self.marker(0)


def _write(tmp_path, data: bytes, name: str = "model.op2") -> Path:
    path = tmp_path / name
    path.write_bytes(data)
    return path


# ------------------------------------------------------------------------------------------------
# the pyNastran-written fixtures
def test_free_fixture_has_flexsats_modes(free):
    """Frequencies from LAMA's λ, shapes from OUGV1: flexsat's, rounded to float32."""
    s, fe = free
    model = read_op2_modes(DATA / "free_frame.op2")
    assert model.boundary == "free" and model.n_modes == 14
    np.testing.assert_array_equal(model.node_ids, s.node_ids)
    np.testing.assert_allclose(model.coordinates, s.coordinates, rtol=F32, atol=0)
    assert np.all(model.frequencies[:6] == 0.0)
    # λ rounded to float32: ω within 2^-25 relative (plus the solve's own roundoff, << 1e-12)
    np.testing.assert_allclose(model.frequencies[6:], fe.omegas[6:], rtol=F32 / 2 + 1e-12)
    expected = fe.at_nodes()
    tiny = 1e-12 * np.abs(expected).max()  # another BLAS: roundoff-level entries differ
    np.testing.assert_allclose(
        _aligned(model.shapes, expected), expected, rtol=F32 * (1 + 1e-6), atol=tiny
    )


def test_free_fixture_mass_properties_from_rigid_modes(free):
    """No mass matrix in an OP2: M_rr and L from the rigid-body modes equal R^T M R, Φ^T M R."""
    _, fe = free
    model = read_op2_modes(DATA / "free_frame.op2")
    exact = _rigid_mass()
    assert _scaled_error(model.rigid_mass, exact, exact) < DERIVED
    L = _participation(fe)
    d = np.sqrt(np.diag(exact))
    assert np.abs(model.participation[6:] / d).max() < DERIVED  # elastic modes carry none
    # the rigid-mode basis is the file's: compare the basis-free L^T L = M_rr
    Lr = model.participation[:6]
    assert _scaled_error(Lr.T @ Lr, L[:6].T @ L[:6], exact) < DERIVED


def test_free_fixture_about_another_reference(free):
    ref = np.array([0.4, -0.2, 0.1])
    model = read_op2_modes(DATA / "free_frame.op2", reference=ref)
    exact = _rigid_mass(ref)
    assert _scaled_error(model.rigid_mass, exact, exact) < DERIVED
    np.testing.assert_array_equal(model.reference, ref)


def test_clamped_fixture_rigid_mass_from_ogpwg(clamped):
    """Cantilevered: participation given, rigid mass OGPWG's M_O (float32 of R^T M R)."""
    s, fe = clamped
    L = _participation(fe)
    model = read_op2_modes(DATA / "clamped_frame.op2", participation=L)
    assert model.boundary == "cantilevered" and model.n_modes == 8
    exact = _rigid_mass()
    assert _scaled_error(model.rigid_mass, exact, exact) < 2 * F32
    np.testing.assert_allclose(model.frequencies, fe.omegas, rtol=F32 / 2 + 1e-12)
    expected = fe.at_nodes()
    tiny = 1e-12 * np.abs(expected).max()
    np.testing.assert_allclose(
        _aligned(model.shapes, expected), expected, rtol=F32 * (1 + 1e-6), atol=tiny
    )
    assert np.all(model.shapes[:, 0] == 0.0)  # the clamped grid 101


def test_clamped_fixture_ogpwg_moved_to_reference(clamped):
    """M = T^T M_O T with T the rigid transfer from the OGPWG point (origin) to ``reference``."""
    _, fe = clamped
    ref = np.array([1.2, 0.0, 0.0])
    model = read_op2_modes(
        DATA / "clamped_frame.op2", reference=ref, participation=_participation(fe, ref)
    )
    exact = _rigid_mass(ref)
    assert _scaled_error(model.rigid_mass, exact, exact) < 4 * F32


def test_raw_tables_of_the_fixture(clamped):
    s, fe = clamped
    raw = read_op2(DATA / "clamped_frame.op2")
    assert raw.eigenvector_table == "OUGV1"
    np.testing.assert_array_equal(raw.mode_numbers, np.arange(1, 9))
    np.testing.assert_allclose(raw.eigenvalues, fe.omegas**2, rtol=F32 + 1e-12)
    np.testing.assert_array_equal(raw.generalized_mass, np.ones(8))
    np.testing.assert_array_equal(raw.gpwg_reference, np.zeros(3))
    assert _scaled_error(raw.gpwg_mass, _rigid_mass(), _rigid_mass()) < 2 * F32


def test_read_nastran_modes_sends_a_lone_op2_here(clamped):
    _, fe = clamped
    L = _participation(fe)
    with pytest.raises(FieldError, match="participation: .* cantilevered model"):
        read_nastran_modes(DATA / "clamped_frame.op2")
    free_a = read_nastran_modes(DATA / "free_frame.op2", damping=0.01)
    free_b = read_op2_modes(DATA / "free_frame.op2", damping=0.01)
    np.testing.assert_array_equal(free_a.shapes, free_b.shapes)
    np.testing.assert_array_equal(free_a.rigid_mass, free_b.rigid_mass)
    assert np.all(free_a.damping == 0.01)
    with pytest.raises(FieldError, match="superelement: a plain SOL 103 OP2"):
        read_nastran_modes(DATA / "free_frame.op2", superelement=2)
    assert read_op2_modes(DATA / "clamped_frame.op2", participation=L).n_modes == 8


def test_model_units(free):
    """mm-kg-ms model: lengths ×1e-3 to m, ω ×1e3 to rad/s, rotation shapes ×1e3 per m."""
    si = read_op2_modes(DATA / "free_frame.op2")
    mm = read_op2_modes(DATA / "free_frame.op2", units={"length": "mm", "mass": "kg", "time": "ms"})
    np.testing.assert_allclose(mm.coordinates, si.coordinates * 1e-3, rtol=1e-15)
    np.testing.assert_allclose(mm.frequencies, si.frequencies * 1e3, rtol=1e-15)
    np.testing.assert_allclose(mm.shapes[..., :3], si.shapes[..., :3], rtol=1e-15)
    np.testing.assert_allclose(mm.shapes[..., 3:], si.shapes[..., 3:] * 1e3, rtol=1e-15)


# ------------------------------------------------------------------------------------------------
# word size and byte order
@pytest.mark.parametrize("word, endian", [(4, "<"), (4, ">"), (8, "<"), (8, ">")])
def test_word_size_and_byte_order(tmp_path, free, word, endian):
    s, fe = free
    path = _write(tmp_path, _Encoder(word, endian).modes(s, fe))
    raw = read_op2(path)
    rtol = F32 if word == 4 else 1e-15  # 64-bit words store reals in double precision
    np.testing.assert_allclose(raw.coordinates, s.coordinates, rtol=rtol, atol=0)
    np.testing.assert_allclose(raw.eigenvalues, fe.omegas**2, rtol=rtol, atol=1e-300)
    np.testing.assert_allclose(raw.shapes, fe.at_nodes(), rtol=rtol, atol=0)
    np.testing.assert_array_equal(raw.node_ids, s.node_ids)


def test_basic_eigenvectors_allow_local_output_systems(tmp_path, free):
    """BOUGV1 is in basic: a grid's CD does not matter; OUGV1 with CD != 0 is refused."""
    s, fe = free
    enc = _Encoder()
    lam, cd = fe.omegas**2, np.arange(len(s.node_ids)) % 2 * 5
    body = enc.header() + enc.geom1(s.node_ids, s.coordinates, cd=cd) + enc.lama(lam)
    basic = _write(tmp_path, body + enc.oug("BOUGV1", s.node_ids, lam, fe.at_nodes()))
    assert read_op2(basic).eigenvector_table == "BOUGV1"
    local = _write(tmp_path, body + enc.oug("OUGV1", s.node_ids, lam, fe.at_nodes()), "cd.op2")
    with pytest.raises(FieldError, match=r"OUGV1 is in the grids' output systems .*\(102, 5\)"):
        read_op2(local)


def test_static_subcase_beside_the_modes_is_skipped(tmp_path, free):
    """A preload subcase writes OUGV1 displacements (approach 1, table 1) before the modes."""
    s, fe = free
    enc = _Encoder()
    lam = fe.omegas**2
    static = enc.oug("OUGV1", s.node_ids, lam[:1], fe.at_nodes()[:1], acode=12, tcode=1)
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates) + static
    data += enc.lama(lam) + enc.oug("OUG1", s.node_ids, lam, fe.at_nodes()) + enc.marker(0)
    raw = read_op2(_write(tmp_path, data))
    assert raw.eigenvector_table == "OUG1" and raw.shapes.shape == (14, 9, 6)


def test_generalized_mass_normalises(tmp_path, clamped):
    """EIGRL NORM=MAX: shapes scaled by c have generalized mass c²; the reader divides by c."""
    s, fe = clamped
    enc = _Encoder(8)
    lam, c = fe.omegas**2, np.linspace(2.0, 5.0, 8)
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates) + enc.lama(lam, c**2)
    data += enc.oug("OUGV1", s.node_ids, lam, fe.at_nodes() * c[:, None, None])
    model = read_op2_modes(
        _write(tmp_path, data + enc.ogpwg(_rigid_mass())), participation=_participation(fe)
    )
    np.testing.assert_allclose(model.shapes, fe.at_nodes(), rtol=1e-14, atol=1e-300)
    bad = data + enc.lama(lam, -c)  # a second LAMA: refused first
    with pytest.raises(FieldError, match="2 LAMA tables"):
        read_op2(_write(tmp_path, bad, "bad.op2"))


# ------------------------------------------------------------------------------------------------
# refusals
def test_missing_file(tmp_path):
    with pytest.raises(FileNotFoundError, match="OP2 file not found"):
        read_op2(tmp_path / "absent.op2")


def test_unknown_word_size(tmp_path):
    path = _write(tmp_path, b"$ a NASTRAN deck, not an OP2\nSOL 103\n")
    with pytest.raises(FieldError, match=r"op2_path: .*model.op2: unknown word size"):
        read_op2(path)


@pytest.mark.parametrize("cut", [3, 100, 2000, -5])
def test_truncated_file(tmp_path, cut):
    data = (DATA / "free_frame.op2").read_bytes()
    path = _write(tmp_path, data[:cut])
    with pytest.raises(FieldError, match="truncated file"):
        read_op2(path)


def test_every_truncation_is_refused(tmp_path):
    """Cut anywhere before the end-of-file marker [0]: a FieldError, never a partial model."""
    data = (DATA / "clamped_frame.op2").read_bytes()
    path = tmp_path / "cut.op2"
    for cut in range(0, len(data) - 12, 37):
        path.write_bytes(data[:cut])
        with pytest.raises(FieldError, match="op2_path: "):
            read_op2(path)
    path.write_bytes(data[:-12])  # only the end-of-file marker lost: every table is whole
    assert read_op2(path).shapes.shape == (8, 9, 6)


def test_corrupted_bytes_never_crash(tmp_path):
    """Random single-byte corruptions: the reader returns finite data or refuses (FieldError)."""
    data = (DATA / "free_frame.op2").read_bytes()
    rng = np.random.default_rng(22)
    path = tmp_path / "flipped.op2"
    for position, value in zip(rng.integers(0, len(data), 400), rng.integers(0, 256, 400)):
        flipped = bytearray(data)
        flipped[position] = value
        path.write_bytes(bytes(flipped))
        try:
            raw = read_op2(path)
        except FieldError:
            continue
        assert np.all(np.isfinite(raw.shapes)) and np.all(np.isfinite(raw.eigenvalues))


def test_non_finite_values_refused(tmp_path, free):
    s, fe = free
    shapes = fe.at_nodes().copy()
    shapes[3, 2, 1] = np.nan
    enc = _Encoder()
    lam = fe.omegas**2
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates) + enc.lama(lam)
    data += enc.oug("OUGV1", s.node_ids, lam, shapes) + enc.marker(0)
    with pytest.raises(FieldError, match=r"non-finite eigenvectors \(OUGV1\)"):
        read_op2(_write(tmp_path, data))


def test_corrupt_length_marker(tmp_path):
    data = bytearray((DATA / "free_frame.op2").read_bytes())
    data[-4] ^= 0x01  # the closing length marker of the last record: 4 -> 5
    with pytest.raises(FieldError, match="corrupt record at byte .* length markers differ"):
        read_op2(_write(tmp_path, bytes(data)))


def test_not_a_sol103_run(tmp_path, free):
    s, fe = free
    enc = _Encoder()
    lam = fe.omegas**2
    geometry = enc.header() + enc.geom1(s.node_ids, s.coordinates)
    with pytest.raises(FieldError, match=r"no eigenvector table .*\['GEOM1', 'LAMA'\].*SOL 103"):
        read_op2(_write(tmp_path, geometry + enc.lama(lam) + enc.marker(0)))
    static = enc.oug("OUGV1", s.node_ids, lam[:1], fe.at_nodes()[:1], acode=12, tcode=1)
    with pytest.raises(FieldError, match="approach code 12, table code 1.*not a SOL 103 run"):
        read_op2(_write(tmp_path, geometry + static + enc.marker(0), "static.op2"))


@pytest.mark.parametrize(
    "oug",
    [
        {"acode": 92},  # complex eigenvalues, device 2
        {"fmt": 2, "width": 14},  # real/imaginary
        {"tcode": 1007},  # sort code 1: complex
    ],
)
def test_complex_eigenvectors(tmp_path, free, oug):
    s, fe = free
    with pytest.raises(FieldError, match="OUGV1 holds complex eigenvectors"):
        read_op2(_write(tmp_path, _Encoder().modes(s, fe, **oug)))


def test_complex_eigenvalues_only(tmp_path, free):
    s, fe = free
    enc = _Encoder()
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates)
    data += enc.table("CLAMA", [enc.ident(91, 9), enc.i(1, 1) + enc.f(0.0, 1.0, 0.0, 0.0)])
    with pytest.raises(FieldError, match=r"complex eigenvalues \(CLAMA\)"):
        read_op2(_write(tmp_path, data + enc.marker(0)))


def test_sort2_and_width(tmp_path, free):
    s, fe = free
    with pytest.raises(FieldError, match="SORT2"):
        read_op2(_write(tmp_path, _Encoder().modes(s, fe, tcode=2007)))
    with pytest.raises(FieldError, match="9 words per point, real eigenvectors have 8"):
        read_op2(_write(tmp_path, _Encoder().modes(s, fe, width=9), "w.op2"))


def test_several_subcases(tmp_path, free):
    s, fe = free
    subcases = [1] * 7 + [2] * 7
    with pytest.raises(FieldError, match=r"subcases \[1, 2\]"):
        read_op2(_write(tmp_path, _Encoder().modes(s, fe, subcases=subcases)))


def test_grids_without_geometry_or_in_local_systems(tmp_path, free):
    s, fe = free
    enc = _Encoder()
    lam = fe.omegas**2
    modes = enc.lama(lam) + enc.oug("OUGV1", s.node_ids, lam, fe.at_nodes()) + enc.marker(0)
    with pytest.raises(FieldError, match=r"no GRID records \(table GEOM1 or GEOM1S\)"):
        read_op2(_write(tmp_path, enc.header() + modes))
    few = enc.geom1(s.node_ids[:-1], s.coordinates[:-1])
    with pytest.raises(FieldError, match=r"grids \[109\] have eigenvectors in OUGV1 but no GRID"):
        read_op2(_write(tmp_path, enc.header() + few + modes, "few.op2"))
    cp = np.zeros(len(s.node_ids), int)
    cp[3] = 7
    local = enc.geom1(s.node_ids, s.coordinates, cp=cp)
    with pytest.raises(FieldError, match=r"coordinate systems other than basic .*\(104, 7\)"):
        read_op2(_write(tmp_path, enc.header() + local + modes, "cp.op2"))


def test_mode_without_eigenvalue(tmp_path, free):
    s, fe = free
    enc = _Encoder()
    lam = fe.omegas**2
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates) + enc.lama(lam[:10])
    data += enc.oug("OUGV1", s.node_ids, lam, fe.at_nodes()) + enc.marker(0)
    with pytest.raises(FieldError, match=r"modes \[11, 12, 13, 14\] of OUGV1 have no LAMA"):
        read_op2(_write(tmp_path, data))


def test_unstable_model_refused(tmp_path, clamped):
    """λ < 0 beyond rigid-body roundoff (a buckled prestressed run) is no rigid-body mode."""
    s, fe = clamped
    enc = _Encoder()
    lam = fe.omegas**2
    lam[0] = -2.5e3
    data = enc.header() + enc.geom1(s.node_ids, s.coordinates) + enc.lama(lam)
    data += enc.oug("OUGV1", s.node_ids, lam, fe.at_nodes()) + enc.marker(0)
    with pytest.raises(FieldError, match=r"rigid_frequency: mode 1 has eigenvalue -2500 < 0"):
        read_op2_modes(_write(tmp_path, data), participation=_participation(fe))


def test_wtmass_scales_ogpwg(clamped):
    _, fe = clamped
    L = _participation(fe)
    path = DATA / "clamped_frame.op2"
    half = read_op2_modes(path, participation=L * np.sqrt(0.5), wtmass=0.5)
    exact = _rigid_mass()
    assert _scaled_error(half.rigid_mass, 0.5 * exact, exact) < 2 * F32
    with pytest.raises(FieldError, match="wtmass: "):
        read_op2_modes(path, participation=L, wtmass=0.0)


def test_cantilevered_mass_properties_must_be_given(tmp_path, clamped):
    s, fe = clamped
    path = _write(tmp_path, _Encoder().modes(s, fe))  # no OGPWG
    with pytest.raises(FieldError, match="participation: .*cantilevered model"):
        read_op2_modes(path)
    with pytest.raises(FieldError, match=r"rigid_mass: .*no OGPWG table"):
        read_op2_modes(path, participation=_participation(fe))
    model = read_op2_modes(path, rigid_mass=_rigid_mass(), participation=_participation(fe))
    assert model.boundary == "cantilevered"
