r"""The normal modes of a plain NASTRAN SOL 103 OP2 file, read with numpy alone.

An OP2 written by ``PARAM,POST,-1`` (MSC or NX NASTRAN) holds the real eigenvectors OUGV1
(OUG1 from MSC Nastran 2021 on; BOUGV1 or BOUG1 in basic), usually the eigenvalue table LAMA,
the geometry GEOM1/GEOM1S and, with ``PARAM,GRDPNT``, the grid point weight generator table
OGPWG. Every other table (elements, stresses, matrices) is skipped. No NASTRAN DMAP (NAS2CAM) and no
OP4 are needed; :func:`flexsat.structures.read_nastran_modes` sends an OP2 without an OP4 here.

Format
------
From the DMAP Programmer's Guide: MSC Software Corporation, *MSC Nastran 2021 DMAP
Programmer's Guide*, chapter 2 "Data Blocks" (the OUTPUT2 file: table name, trailer and
records; OUG, LAMA, GEOM1 and OGPWG), and Siemens PLM Software, *NX Nastran 12 DMAP
Programmer's Guide*, same chapter.

*Records.* The file is Fortran unformatted, sequential: each record is
``[n bytes][payload][n bytes]``. A word is 4 bytes (32-bit) or 8 bytes (64-bit build); the
length markers are 4-byte integers in both, in the file's byte order. The first record holds
one word (``3``), which gives the word size (4 or 8 bytes) and the byte order.

A logical record is ``[n] [n words]``, where ``[k]`` is a one-word record, continued by
further ``[n] [n words]`` pieces while the next one-word record is positive (long records are
split; MSC Nastran 2014 and later append a version piece to the header label and to each table
name).

*Header* (``PARAM,POST,-1``; ``POST,-2`` files start with their first table):
``[3] [date] [7] ["NASTRAN FORT TAPE ID CODE - "] [2] [label] [-1] [0]``.

*Table*: ``[2] [name, 8 characters]``, ``[-1] [7] [trailer, 7 words]``, then records
``[-2] [1] [0] [n] [n words]``, ``[-3] [1] [0] ...`` and so on (``[-k] [1] [1]`` before a
matrix column); ``[-k] [1] [0] [0]`` ends the table and ``[0]`` the file. Record -2 is the
header; in OUG, LAMA and OGPWG the records from -3 on alternate between a 146-word
identification record (IDENT) and a data record.

*LAMA* data: per mode 7 words ``(mode, extraction order, λ, ω, f, generalized mass,
generalized stiffness)``, two integers then five reals. Files without LAMA (older runs) carry
each mode's λ in word 6 of its eigenvector IDENT record, read instead; their shapes are taken
as mass-normalised (NASTRAN's default, EIGRL NORM=MASS).

*OUGV1 / BOUGV1* IDENT: word 1 approach code = 10 × analysis + device (analysis 2: real
eigenvalues, 9: complex eigenvalues), word 2 table code + 1000 × sort code (table code 7:
eigenvector; sort code bits 1 complex, 2 SORT2, 4 random), word 4 subcase, word 5 mode number,
word 6 λ, word 9 format code (1 real, 2 real/imaginary, 3 magnitude/phase), word 10 words per
point (8 real, 14 complex). Data, SORT1 real: per point ``(10 × id + device, point type, T1,
T2, T3, R1, R2, R3)``, point type 1 for a GRID. OUGV1 is in each grid's output system (CD),
BOUGV1 (``PARAM,OUGCORD,BASIC``) in basic.

*GEOM1 / GEOM1S*: each record starts with a 3-word key; GRID is ``(4501, 45, 1)`` with 8 words
per grid ``(ID, CP, X1, X2, X3, CD, PS, SEID)``, X in system CP (MSC's double-precision GRID
record ``(4501, 45, 1120001)`` has X1-X3 in 8-byte reals).

*OGPWG*: IDENT word 3 the reference point (0: the basic origin); data 78 words, the first 36 the
rigid-body mass matrix :math:`M_O` in basic about the reference point, in the input mass units
(before ``PARAM,WTMASS``).

Coordinate systems
------------------
Grids whose location system CP is not basic (0) are refused, as are grids whose output system
CD is not basic when the eigenvectors are OUGV1: no CORD table is read, so neither can be
transformed; request ``PARAM,OUGCORD,BASIC`` (BOUGV1) for the second.

Mass properties
---------------
A free model (six rigid-body modes) gives its rigid mass and participation from the rigid-body
modes (:func:`flexsat.structures.modal_import.mass_properties_from_modes`). A cantilevered one
has no mass matrix in the file: its participation :math:`L = \Phi^T M R` must be given, and its
rigid mass is OGPWG's :math:`M_O` times ``wtmass``, moved to ``reference`` by the rigid transfer

.. math::

    M = T^T M_O T, \qquad T = \begin{bmatrix} I & [(p - p_0)\times] \\ 0 & I \end{bmatrix},

(:math:`p_0` the OGPWG reference point, p the ``reference``), unless ``rigid_mass`` is given.
"""

from __future__ import annotations

import errno
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import (
    FieldError,
    require_finite,
    require_nonneg,
    require_positive_scalar,
)
from flexsat.structures.modal_import import (
    eigen_frequencies,
    mass_properties_from_modes,
    unit_scales,
)
from flexsat.structures.modal_model import RIGID_FREQUENCY, ModalModel
from flexsat.units import FloatArray

__all__ = ["Op2Modes", "read_op2", "read_op2_modes"]

_EIGENVECTOR_TABLES = ("BOUGV1", "BOUG1", "OUGV1", "OUG1")  # B: in basic; OUG1 in MSC >= 2021
_COMPLEX_EIGENVALUE_TABLES = ("CLAMA",)
_GEOMETRY_TABLES = ("GEOM1", "GEOM1S")
_KEPT = {"LAMA", "OGPWG", *_EIGENVECTOR_TABLES, *_COMPLEX_EIGENVALUE_TABLES, *_GEOMETRY_TABLES}
_GRID_KEYS = {(4501, 45, 1): False, (4501, 45, 810001): False, (4501, 45, 1120001): True}
_REAL_EIGENVALUES, _COMPLEX_EIGENVALUES = 2, 9  # analysis codes (approach code // 10)
_EIGENVECTOR_TABLE_CODE = 7
_LAMA_WORDS, _GRID_WORDS, _OGPWG_WORDS, _REAL_POINT_WORDS = 7, 8, 78, 8
_GRID_POINT = 1  # point type of a GRID in OUG data (scalar and extra points are others)


@dataclass(frozen=True)
class Op2Modes:
    """Normal modes as an OP2 stores them: model units, basic coordinates.

    Attributes
    ----------
    eigenvalues : ndarray (m,)
        λ = ω² of the modes read, (rad / model time unit)², in mode-number order: from LAMA,
        else from the eigenvector table's IDENT records.
    generalized_mass : ndarray (m,) or None
        φᵀ M φ from LAMA (1 for mass-normalised eigenvectors); None without LAMA.
    mode_numbers : ndarray (m,)
    node_ids : ndarray (n,)
        GRID ids in the order of the eigenvector table.
    coordinates : ndarray (n, 3)
        Basic coordinates, model length units.
    shapes : ndarray (m, n, 6)
        T1, T2, T3, R1, R2, R3 in basic.
    eigenvector_table : str
        The table read: "OUGV1" or "OUG1" (grids' output systems, all basic), "BOUGV1" or
        "BOUG1" (basic).
    gpwg_mass : ndarray (6, 6) or None
        OGPWG's rigid-body mass matrix :math:`M_O` (input mass units), if the table is present.
    gpwg_reference : ndarray (3,) or None
        The point :math:`M_O` is about, basic, model length units.
    """

    eigenvalues: FloatArray
    generalized_mass: FloatArray | None
    mode_numbers: npt.NDArray[np.int64]
    node_ids: npt.NDArray[np.int64]
    coordinates: FloatArray
    shapes: FloatArray
    eigenvector_table: str
    gpwg_mass: FloatArray | None
    gpwg_reference: FloatArray | None


# ------------------------------------------------------------------------------------------------
# Fortran records and tables
def _refuse(path: Path, rule: str) -> FieldError:
    return FieldError("op2_path", f"{path}: {rule}")


@dataclass(frozen=True)
class _Layout:
    """Word size (4 or 8 bytes) and byte order ("<" or ">") of an OP2."""

    word: int
    endian: str

    def ints(self, payload: bytes) -> npt.NDArray[np.int64]:
        return np.frombuffer(payload, f"{self.endian}i{self.word}").astype(np.int64)

    def floats(self, payload: bytes) -> FloatArray:
        return np.frombuffer(payload, f"{self.endian}f{self.word}").astype(float)


def _layout(data: bytes, path: Path) -> _Layout:
    """The first record is one word: its 4-byte length marker gives word size and byte order."""
    if len(data) < 4:
        raise _refuse(path, f"truncated file: {len(data)} bytes, no first record")
    orders: tuple[tuple[str, Literal["little", "big"]], ...] = (("<", "little"), (">", "big"))
    for endian, order in orders:
        n = int.from_bytes(data[:4], order, signed=True)
        if n in (4, 8):
            return _Layout(n, endian)
    raise _refuse(
        path,
        "unknown word size: the first record is "
        f"{int.from_bytes(data[:4], 'little', signed=True)} bytes long (little-endian) or "
        f"{int.from_bytes(data[:4], 'big', signed=True)} (big-endian), not 4 (32-bit words) or "
        "8 (64-bit): not an OP2 file",
    )


class _Records:
    """The Fortran records of an OP2, read in order."""

    def __init__(self, data: bytes, layout: _Layout, path: Path) -> None:
        self.data, self.layout, self.path = data, layout, path
        self.pos = 0
        self.table = ""  # the table being read, for messages

    def at_end(self) -> bool:
        return self.pos >= len(self.data)

    def _where(self) -> str:
        return f" in table {self.table}" if self.table else ""

    def payload(self) -> bytes:
        fmt = self.layout.endian + "i"
        start, size = self.pos, len(self.data)
        if start + 4 > size:
            raise _refuse(self.path, f"truncated file: ends at byte {size}{self._where()}")
        (n,) = struct.unpack_from(fmt, self.data, start)
        end = start + 4 + n
        if n < 0 or end + 4 > size:
            raise _refuse(
                self.path,
                f"truncated file: the record at byte {start}{self._where()} announces {n} bytes, "
                f"the file ends at byte {size}",
            )
        (closing,) = struct.unpack_from(fmt, self.data, end)
        if closing != n:
            raise _refuse(
                self.path,
                f"corrupt record at byte {start}{self._where()}: its length markers differ "
                f"({n} and {closing})",
            )
        self.pos = end + 4
        return self.data[start + 4 : end]

    def peek(self) -> int:
        """The next one-word marker, left unread."""
        pos = self.pos
        value = self.marker()
        self.pos = pos
        return value

    def record(self) -> list[bytes]:
        """A logical record: ``[n] [n words]`` pieces while the next marker is positive."""
        pieces = []
        while self.peek() > 0:  # n counts words in tables, terms in matrices: not checked
            self.marker()
            pieces.append(self.payload())
            if len(pieces[-1]) % self.layout.word:
                raise _refuse(
                    self.path,
                    f"corrupt record{self._where()} ending at byte {self.pos}: {len(pieces[-1])} "
                    f"bytes is not a whole number of {self.layout.word}-byte words",
                )
        return pieces

    def marker(self) -> int:
        payload = self.payload()
        if len(payload) != self.layout.word:
            raise _refuse(
                self.path,
                f"corrupt file: a one-word marker record{self._where()} before byte {self.pos} "
                f"has {len(payload)} bytes",
            )
        return int(self.layout.ints(payload)[0])

    def expect(self, *markers: int) -> None:
        for expected in markers:
            got = self.marker()
            if got != expected:
                raise _refuse(
                    self.path,
                    f"corrupt file: marker {got} where {expected} belongs{self._where()} "
                    f"(record ending at byte {self.pos})",
                )


def _table_name(payload: bytes, word: int) -> str:
    """8-character name; 64-bit files store it in 16 bytes, NX interlacing 4 + 4 blanks."""
    if word == 8 and len(payload) >= 16 and payload[4:8] == b"    ":
        payload = payload[0:4] + payload[8:12]
    return payload[:8].decode("latin-1").strip()


def _read_tables(records: _Records) -> tuple[dict[str, list[list[bytes]]], list[str]]:
    """Records (from -2 on) of the tables kept, by name, and the names of all tables."""
    if records.peek() == 3:  # PARAM,POST,-1 header: date, tape code, label (+ MSC version)
        for _ in range(3):
            records.record()
        records.expect(-1, 0)
    kept: dict[str, list[list[bytes]]] = {}
    names: list[str] = []
    while not records.at_end():
        if records.peek() == 0:  # end of file
            break
        if records.peek() < 0:
            raise _refuse(
                records.path, f"corrupt file: marker {records.peek()} where a table name belongs"
            )
        name = _table_name(records.record()[0], records.layout.word)  # + MSC version pieces
        records.table = name
        names.append(name)
        records.expect(-1)
        records.record()  # trailer
        records.expect(-2)
        body: list[bytes] = []
        number = -2
        while True:
            records.expect(1)
            records.marker()  # 0 in tables, 1 in matrix columns
            if records.peek() == 0:
                records.marker()
                break
            pieces = records.record()
            body.append(b"".join(pieces) if name in _KEPT else b"")  # others: walked, not kept
            number -= 1
            n = records.marker()
            if n != number:
                raise _refuse(
                    records.path, f"corrupt file: record {n} where {number} belongs in table {name}"
                )
        if name in _KEPT:
            kept.setdefault(name, []).append(body)
        records.table = ""
    return kept, names


# ------------------------------------------------------------------------------------------------
# tables
def _words(layout: _Layout, payload: bytes, width: int, what: str, path: Path) -> int:
    """Number of entries of ``width`` words in ``payload``, refused when it does not divide."""
    words, rest = divmod(len(payload), layout.word)
    if rest or words % width:
        raise _refuse(
            path,
            f"corrupt {what}: {len(payload)} bytes is not a whole number of {width}-word entries",
        )
    return words // width


def _single(tables: dict[str, list[list[bytes]]], name: str, path: Path) -> list[bytes]:
    if len(tables[name]) > 1:
        raise _refuse(path, f"{len(tables[name])} {name} tables (one SOL 103 subcase is read)")
    return tables[name][0]


def _eigenvalues(
    tables: dict[str, list[list[bytes]]], layout: _Layout, path: Path
) -> dict[int, tuple[float, float]]:
    """LAMA: mode number -> (λ, generalized mass)."""
    body = _single(tables, "LAMA", path)
    if len(body) != 3:
        raise _refuse(
            path, f"LAMA has {len(body) - 1} records after its header, expected 2 (one subcase)"
        )
    _words(layout, body[2], _LAMA_WORDS, "LAMA data record", path)
    ints = layout.ints(body[2]).reshape(-1, _LAMA_WORDS)
    reals = layout.floats(body[2]).reshape(-1, _LAMA_WORDS)
    return {
        int(i): (float(lam), float(mu)) for i, lam, mu in zip(ints[:, 0], reals[:, 2], reals[:, 5])
    }


def _check_ident(ident: npt.NDArray[np.int64], name: str, path: Path) -> None:
    if ident.size < 10:
        raise _refuse(path, f"corrupt {name}: an IDENT record of {ident.size} words, not 146")
    analysis, table_code, sort_code = ident[0] // 10, ident[1] % 1000, ident[1] // 1000
    format_code, width = ident[8], ident[9]
    if analysis == _COMPLEX_EIGENVALUES or sort_code & 1 or format_code in (2, 3):
        raise _refuse(
            path,
            f"{name} holds complex eigenvectors (approach code {ident[0]}, format code "
            f"{format_code}); only real normal modes (SOL 103) are read",
        )
    if analysis != _REAL_EIGENVALUES or table_code != _EIGENVECTOR_TABLE_CODE:
        raise _refuse(
            path,
            f"{name} is not a table of real eigenvectors (approach code {ident[0]}, table code "
            f"{ident[1]}; eigenvectors have analysis code 2 and table code 7): not a SOL 103 run",
        )
    if sort_code & 2:
        raise _refuse(path, f"{name} is in SORT2 (table code {ident[1]}); only SORT1 is read")
    if width != _REAL_POINT_WORDS:
        raise _refuse(path, f"{name} has {width} words per point, real eigenvectors have 8")


def _eigenvector_table(
    tables: dict[str, list[list[bytes]]], layout: _Layout, path: Path, names: list[str]
) -> tuple[str, list[bytes]]:
    """The one OUG table of real eigenvectors (in basic if there is one), name and records.

    A SOL 103 run with a static subcase (preload) also has an OUG table of displacements.
    """
    candidates = [(name, body) for name in _EIGENVECTOR_TABLES for body in tables.get(name, [])]
    if not candidates:
        raise _refuse(
            path,
            f"no eigenvector table OUGV1, OUG1, BOUGV1 or BOUG1 (tables {names}): not the OP2 "
            "of a SOL 103 normal-modes run (a NAS2CAM OP2 needs its OP4)",
        )
    real, refusals = [], []
    for name, body in candidates:
        if len(body) < 3 or len(body) % 2 == 0:
            refusals.append(
                _refuse(
                    path,
                    f"{name} has {len(body) - 1} records after its header, expected IDENT and "
                    "data record pairs",
                )
            )
            continue
        try:
            _check_ident(layout.ints(body[1]), name, path)
        except FieldError as refusal:
            refusals.append(refusal)
            continue
        real.append((name, body))
    if not real:
        raise refusals[0]
    chosen = [c for c in real if c[0].startswith("B")] or real
    if len(chosen) > 1:
        raise _refuse(
            path,
            f"{len(chosen)} tables of real eigenvectors ({', '.join(c[0] for c in chosen)}): "
            "one SOL 103 subcase is read",
        )
    return chosen[0]


def _eigenvectors(
    name: str, body: list[bytes], layout: _Layout, path: Path
) -> tuple[npt.NDArray[np.int64], FloatArray, npt.NDArray[np.int64], FloatArray]:
    """Mode numbers (m,), λ (m,), GRID ids (n,) and values (m, n, 6) of an eigenvector table."""
    modes: list[int] = []
    eigenvalues: list[float] = []
    subcases: set[int] = set()
    values: list[FloatArray] = []
    ids: npt.NDArray[np.int64] | None = None
    for ident_payload, data in zip(body[1::2], body[2::2]):
        ident = layout.ints(ident_payload)
        _check_ident(ident, name, path)
        _words(layout, data, _REAL_POINT_WORDS, f"{name} data record", path)
        ints = layout.ints(data).reshape(-1, _REAL_POINT_WORDS)
        grids = ints[:, 1] == _GRID_POINT
        point_ids = ints[grids, 0] // 10
        if ids is None:
            ids = point_ids
        elif not np.array_equal(ids, point_ids):
            raise _refuse(path, f"{name}: mode {ident[4]} lists other grids than mode {modes[0]}")
        modes.append(int(ident[4]))
        eigenvalues.append(float(layout.floats(ident_payload)[5]))
        subcases.add(int(ident[3]))
        values.append(layout.floats(data).reshape(-1, _REAL_POINT_WORDS)[grids, 2:])
    if len(subcases) > 1:
        raise _refuse(
            path, f"{name} holds subcases {sorted(subcases)}; one SOL 103 subcase is read"
        )
    if len(set(modes)) != len(modes):
        raise _refuse(path, f"{name} holds a mode number twice")
    order = np.argsort(modes)
    assert ids is not None  # at least one pair, checked above
    return np.asarray(modes)[order], np.asarray(eigenvalues)[order], ids, np.stack(values)[order]


def _grid_entries(
    layout: _Layout, entries: bytes, double: bool, name: str, path: Path
) -> tuple[npt.NDArray[np.int64], FloatArray]:
    """(ID, CP, CD) columns and X (k, 3) of a GRID record's entries.

    Single precision: 8 words ``(ID, CP, X1, X2, X3, CD, PS, SEID)``. MSC's double-precision
    GRID record (key 4501, 45, 1120001) stores X1-X3 as 8-byte reals: 11 words in a 32-bit file.
    """
    if double and layout.word == 4:
        k = _words(layout, entries, _GRID_WORDS + 3, f"{name} GRID record", path)
        rows = np.frombuffer(entries, np.uint8).reshape(k, 4 * (_GRID_WORDS + 3))
        ints = layout.ints(rows[:, [*range(8), *range(32, 44)]].tobytes()).reshape(k, 5)
        x = np.frombuffer(rows[:, 8:32].tobytes(), f"{layout.endian}f8").reshape(k, 3)
        return ints[:, [0, 1, 2]], x.astype(float)
    k = _words(layout, entries, _GRID_WORDS, f"{name} GRID record", path)
    ints = layout.ints(entries).reshape(k, _GRID_WORDS)
    return ints[:, [0, 1, 5]], layout.floats(entries).reshape(k, _GRID_WORDS)[:, 2:5]


def _grids(
    tables: dict[str, list[list[bytes]]], layout: _Layout, path: Path
) -> dict[int, tuple[int, FloatArray, int]]:
    """GRID id -> (CP, X, CD) from every GEOM1/GEOM1S GRID record."""
    grids: dict[int, tuple[int, FloatArray, int]] = {}
    for name in _GEOMETRY_TABLES:
        for body in tables.get(name, []):
            for payload in body[1:]:
                if len(payload) < 3 * layout.word:
                    continue
                key = tuple(int(k) for k in layout.ints(payload[: 3 * layout.word]))
                if key not in _GRID_KEYS:
                    continue
                ids, x = _grid_entries(
                    layout, payload[3 * layout.word :], _GRID_KEYS[key], name, path
                )
                for (nid, cp, cd), xyz in zip(ids, x):
                    grids[int(nid)] = (int(cp), xyz, int(cd))
    return grids


def _coordinates(
    grids: dict[int, tuple[int, FloatArray, int]],
    ids: npt.NDArray[np.int64],
    table: str,
    path: Path,
) -> FloatArray:
    """Basic coordinates of the eigenvector grids; refused where a system is not basic."""
    if not grids:
        raise _refuse(
            path,
            "no GRID records (table GEOM1 or GEOM1S): grid locations unknown; "
            "write the geometry with PARAM,POST,-1",
        )
    missing = [int(i) for i in ids if int(i) not in grids]
    if missing:
        raise _refuse(path, f"grids {missing[:8]} have eigenvectors in {table} but no GRID record")
    local_cp = [(int(i), grids[int(i)][0]) for i in ids if grids[int(i)][0] != 0]
    if local_cp:
        raise _refuse(
            path,
            "grid locations in coordinate systems other than basic (grid, CP) "
            f"{local_cp[:8]}: not supported (no CORD table is read)",
        )
    local_cd = [(int(i), grids[int(i)][2]) for i in ids if grids[int(i)][2] != 0]
    if local_cd and not table.startswith("B"):
        raise _refuse(
            path,
            f"{table} is in the grids' output systems and these are not basic (grid, CD) "
            f"{local_cd[:8]}: request PARAM,OUGCORD,BASIC (eigenvectors in BOUGV1)",
        )
    return np.array([grids[int(i)][1] for i in ids])


def _grid_point_weight(
    tables: dict[str, list[list[bytes]]],
    layout: _Layout,
    grids: dict[int, tuple[int, FloatArray, int]],
    path: Path,
) -> tuple[FloatArray | None, FloatArray | None]:
    """OGPWG's M_O and its reference point in basic, or (None, None)."""
    if "OGPWG" not in tables:
        return None, None
    body = _single(tables, "OGPWG", path)
    if len(body) != 3 or _words(layout, body[2], _OGPWG_WORDS, "OGPWG data record", path) != 1:
        raise _refuse(path, "OGPWG is not one IDENT record and one 78-word data record")
    head = layout.ints(body[1])
    if head.size < 3:
        raise _refuse(path, f"corrupt OGPWG: an IDENT record of {head.size} words, not 146")
    point = int(head[2])
    if point == 0:
        reference = np.zeros(3)
    elif point in grids and grids[point][0] == 0:
        reference = grids[point][1]
    else:
        raise _refuse(path, f"OGPWG reference point {point} has no GRID record in basic")
    return layout.floats(body[2])[:36].reshape(6, 6), reference


def read_op2(op2_path: str | Path) -> Op2Modes:
    """Real normal modes, grid locations and grid point weight of a SOL 103 OP2, model units.

    Parameters
    ----------
    op2_path : str or path
        An OP2 written with ``PARAM,POST,-1`` (32- or 64-bit words, either byte order).

    Returns
    -------
    Op2Modes
        Modes in mode-number order, grids in the order of the eigenvector table; tables other
        than LAMA, OUGV1/BOUGV1, GEOM1/GEOM1S (GRID records) and OGPWG are skipped.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    FieldError
        Field ``op2_path``, the message naming the file and the reason: unknown word size,
        truncated or corrupt records, no OUGV1/BOUGV1 or one that holds no real eigenvectors
        (not a SOL 103 run), complex eigenvalues (CLAMA) or eigenvectors, SORT2, several
        subcases, a mode without eigenvalue, grids without a
        GRID record or in a non-basic location (CP) or output (CD, with OUGV1) system.
    """
    path = Path(op2_path)
    if not path.is_file():
        raise FileNotFoundError(errno.ENOENT, "NASTRAN OP2 file not found", str(path))
    data = path.read_bytes()
    layout = _layout(data, path)
    tables, names = _read_tables(_Records(data, layout, path))
    if "LAMA" not in tables and any(n in tables for n in _COMPLEX_EIGENVALUE_TABLES):
        raise _refuse(path, "complex eigenvalues (CLAMA) and no LAMA: not a real SOL 103 run")
    table, body = _eigenvector_table(tables, layout, path, names)
    modes, eigenvalues, ids, shapes = _eigenvectors(table, body, layout, path)
    generalized_mass = None
    if "LAMA" in tables:
        lama = _eigenvalues(tables, layout, path)
        unknown = [int(m) for m in modes if int(m) not in lama]
        if unknown:
            raise _refuse(path, f"modes {unknown[:8]} of {table} have no LAMA eigenvalue")
        eigenvalues = np.array([lama[int(m)][0] for m in modes])
        generalized_mass = np.array([lama[int(m)][1] for m in modes])
    grids = _grids(tables, layout, path)
    gpwg_mass, gpwg_reference = _grid_point_weight(tables, layout, grids, path)
    coordinates = _coordinates(grids, ids, table, path)
    for what, values in (
        (f"eigenvalues ({'LAMA' if generalized_mass is not None else table})", eigenvalues),
        (f"eigenvectors ({table})", shapes),
        ("grid locations (GRID)", coordinates),
        ("grid point weight (OGPWG)", np.zeros(0) if gpwg_mass is None else gpwg_mass),
    ):
        if not np.all(np.isfinite(values)):
            raise _refuse(path, f"non-finite {what}: corrupt file")
    return Op2Modes(
        eigenvalues=eigenvalues,
        generalized_mass=generalized_mass,
        mode_numbers=modes,
        node_ids=ids,
        coordinates=coordinates,
        shapes=shapes,
        eigenvector_table=table,
        gpwg_mass=gpwg_mass,
        gpwg_reference=gpwg_reference,
    )


# ------------------------------------------------------------------------------------------------
# modal model
def _transfer(M0: FloatArray, p0: FloatArray, p: FloatArray) -> FloatArray:
    """Rigid mass about p from the one about p0: Tᵀ M0 T, T = [[I, [(p - p0)×]], [0, I]]."""
    x, y, z = p - p0
    T = np.eye(6)
    T[:3, 3:] = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]]
    return T.T @ M0 @ T


def _mass_normalised(modes: Op2Modes, path: Path) -> FloatArray:
    """Shapes divided by √(generalized mass) from LAMA (EIGRL NORM=MAX); as stored without."""
    if modes.generalized_mass is None:
        return modes.shapes
    mu = modes.generalized_mass
    if np.any(mu <= 0.0):
        bad = [int(m) for m in modes.mode_numbers[mu <= 0.0]]
        raise _refuse(path, f"modes {bad[:8]} have generalized mass <= 0 in LAMA")
    return modes.shapes / np.sqrt(mu)[:, None, None]


def read_op2_modes(
    op2_path: str | Path,
    damping: npt.ArrayLike = 0.0,
    reference: npt.ArrayLike = (0.0, 0.0, 0.0),
    units: Mapping[str, str] | None = None,
    rigid_mass: npt.ArrayLike | None = None,
    participation: npt.ArrayLike | None = None,
    wtmass: float = 1.0,
    rigid_frequency: float = RIGID_FREQUENCY,
) -> ModalModel:
    r"""Modal model of a plain SOL 103 OP2 (no OP4, no DMAP).

    Parameters
    ----------
    op2_path : str or path
        See :func:`read_op2`.
    damping : float or array_like (m,)
        Modal damping ratios ζ (NASTRAN modes carry none).
    reference : array_like (3,)
        Point of the rigid-body motion in basic coordinates, model length units.
    units : mapping, optional
        Pint unit strings of the model's ``"length"``, ``"mass"`` and ``"time"``; default SI.
    rigid_mass, participation : array_like (6, 6) and (m, 6), optional
        Model units, about ``reference``, modes in mode-number order. A free model (six
        rigid-body modes) derives both from its rigid-body modes when neither is given. A
        cantilevered one needs ``participation``; its ``rigid_mass`` defaults to OGPWG's
        :math:`M_O` (times ``wtmass``, moved to ``reference``).
    wtmass : float
        ``PARAM,WTMASS`` of the run: OGPWG is in input mass units, the eigenvectors normalised
        to ``wtmass`` times that mass.
    rigid_frequency : float
        Modes at or below this ω, rad/s, are rigid-body modes (ω set to 0).

    Returns
    -------
    ModalModel
        SI; "free" with rigid-body modes, else "cantilevered". Frequencies
        :math:`\sqrt{\max(\lambda, 0)}`; shapes divided by the square root of LAMA's
        generalized mass (1 for NASTRAN's default mass normalisation), taken as
        mass-normalised when the file has no LAMA.

    Raises
    ------
    FileNotFoundError, FieldError
        As :func:`read_op2`; and ``participation`` missing for a cantilevered model, or
        ``rigid_mass`` with no OGPWG to default to, named.
    """
    modes = read_op2(op2_path)
    path = Path(op2_path)
    length, mass_unit, time = unit_scales(units)
    s = np.sqrt(mass_unit) * np.array([1.0, 1.0, 1.0, length, length, length])
    ref = require_finite(reference, "reference")
    if ref.shape != (3,):
        raise FieldError("reference", f"must have shape (3,), got {ref.shape}")
    frequencies = eigen_frequencies(
        modes.eigenvalues, time, float(require_nonneg(rigid_frequency, "rigid_frequency"))
    )
    if participation is not None and rigid_mass is None:
        if modes.gpwg_mass is None or modes.gpwg_reference is None:
            raise FieldError(
                "rigid_mass",
                f"{path} has no OGPWG table (PARAM,GRDPNT) to take the rigid mass from: give it",
            )
        scale = require_positive_scalar(wtmass, "wtmass")
        rigid_mass = scale * _transfer(modes.gpwg_mass, modes.gpwg_reference, ref)
    if not np.any(frequencies == 0.0) and participation is None:
        raise FieldError(
            "participation",
            f"{path} holds a cantilevered model (no rigid-body mode) and an OP2 has no mass "
            "matrix: give the participation Φᵀ M R (m, 6), model units",
        )
    scaled = {
        "rigid_mass": None
        if rigid_mass is None
        else np.asarray(rigid_mass, float) * np.outer(s, s),
        "participation": None if participation is None else np.asarray(participation, float) * s,
    }
    shapes = _mass_normalised(modes, path) / s
    xyz = modes.coordinates * length
    rigid_si, participation_si, boundary = mass_properties_from_modes(
        frequencies,
        shapes,
        xyz,
        ref * length,
        scaled["rigid_mass"],
        scaled["participation"],
        path,
        "an OP2",
    )
    return ModalModel(
        node_ids=modes.node_ids,
        coordinates=xyz,
        frequencies=frequencies,
        damping=require_nonneg(damping, "damping"),
        shapes=shapes,
        rigid_mass=rigid_si,
        participation=participation_si,
        reference=ref * length,
        boundary=boundary,
    )
