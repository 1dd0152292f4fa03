"""Write the SOL 103 OP2 fixtures of tests/structures/test_io_op2.py (run by hand, never by tests).

Two steps, two interpreters, because pyNastran 1.4 needs numpy < 2 and flexsat runs on numpy 2:

1. ``PYTHONPATH=src python tests/data/op2/make_op2_fixtures.py modes DIR`` (flexsat's venv)
   solves the modes of two small frames with flexsat and saves the numbers to ``DIR/*.npz``.
2. ``/tmp/pnvenv/bin/python tests/data/op2/make_op2_fixtures.py op2 DIR`` (a throwaway venv with
   ``pip install "numpy<2" pyNastran``) hands them to pyNastran's OP2 writer, which writes
   ``DIR/*.op2`` (GEOM1 GRID records, LAMA, OUGV1 eigenvectors, OGPWG for the clamped frame).

The frames are those of test_io_op2.py (kept in step by hand: tests do not import this file).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np


def frame(clamped: bool):  # noqa: ANN201 - runs in either interpreter
    """An L-shaped frame of rectangular aluminium members with a tip mass (distinct modes)."""
    from flexsat.structures import Material, Section, Structure

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


def write_modes(out: Path) -> None:
    for name, clamped in (("free_frame", False), ("clamped_frame", True)):
        s, fe = frame(clamped)
        free = frame(False)[1].assembly  # the weight of the whole frame, supports included
        R = free.rigid_body_vectors()
        rigid_mass = R.T @ (free.M @ R)
        np.savez(
            out / f"{name}.npz",
            node_ids=s.node_ids,
            coordinates=s.coordinates,
            omegas=fe.omegas,
            shapes=fe.at_nodes(),
            rigid_mass=rigid_mass,
        )


def write_op2(out: Path) -> None:
    from pyNastran.op2.op2_geom import OP2Geom
    from pyNastran.op2.result_objects.grid_point_weight import make_grid_point_weight
    from pyNastran.op2.tables.lama_eigenvalues.lama_objects import RealEigenvalues
    from pyNastran.op2.tables.oug.oug_eigenvectors import RealEigenvectorArray

    for name in ("free_frame", "clamped_frame"):
        d = np.load(out / f"{name}.npz")
        model = OP2Geom(debug=False)
        for nid, xyz in zip(d["node_ids"], d["coordinates"]):
            model.add_grid(int(nid), xyz)
        omegas = d["omegas"]
        lam = omegas**2
        nmodes = lam.size
        eig = RealEigenvalues("", "LAMA", nmodes=nmodes)
        eig.mode[:] = eig.extraction_order[:] = np.arange(1, nmodes + 1)
        eig.eigenvalues[:], eig.radians[:] = lam, omegas
        eig.cycles[:] = omegas / (2 * np.pi)
        eig.generalized_mass[:], eig.generalized_stiffness[:] = 1.0, lam
        node_gridtype = np.column_stack([d["node_ids"], np.ones(d["node_ids"].size, int)])
        vectors = RealEigenvectorArray.add_modal_case(
            "OUGV1",
            node_gridtype,
            d["shapes"],
            isubcase=1,
            modes=np.arange(1, nmodes + 1),
            eigenvalues=lam,
            mode_cycles=omegas / (2 * np.pi),
            is_sort1=True,
        )
        vectors.table_code = vectors.data_code["table_code"] = 7  # eigenvectors, not displacements
        model.eigenvectors[1] = vectors
        if name == "clamped_frame":
            model.grid_point_weight[""] = make_grid_point_weight(0, d["rigid_mass"])
        path = out / f"{name}.op2"
        model.write_op2(str(path), post=-1, endian=b"<", nastran_format="msc")
        insert_lama(path, eig)


def insert_lama(path: Path, eig) -> None:  # noqa: ANN001 - pyNastran's RealEigenvalues
    """Put the LAMA table, written by pyNastran's RealEigenvalues.write_op2, before OUGV1.

    pyNastran 1.4.1's OP2.write_op2 skips LAMA (``skip_tables`` in op2_writer.py) although the
    table object can write itself; the framing after it is that of op2_writer._write_result_tables:
    the end-of-record markers [itable, 1, 0] and the end-of-table marker [0].
    """
    import io
    import struct

    from pyNastran.op2.writer.op2_writer import TrashWriter

    buf = io.BytesIO()
    itable = eig.write_op2(buf, TrashWriter(), -1, True, (1, 1, 2026), endian=b"<")
    buf.write(struct.pack("<9i", 4, itable, 4, 4, 1, 4, 4, 0, 4))
    buf.write(struct.pack("<3i", 4, 0, 4))
    data = path.read_bytes()
    start = data.index(struct.pack("<4i8si", 4, 2, 4, 8, b"OUGV1   ", 8))
    path.write_bytes(data[:start] + buf.getvalue() + data[start:])


if __name__ == "__main__":
    step, folder = sys.argv[1], Path(sys.argv[2])
    {"modes": write_modes, "op2": write_op2}[step](folder)
