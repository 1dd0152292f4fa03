r"""NASTRAN modal data (OP2/OP4 written by the NAS2CAM DMAP) as a :class:`ModalModel`.

Reading is done by the optional dependency pyyeti (``pip install 'flexsat[nastran]'``):
:func:`pyyeti.nastran.op2.rdnas2cam` returns, per superelement, the USET table (grid locations
and output coordinate systems), the eigenvalues ``lambda``, the g-set mode shapes ``phg`` and the
mass ``maa`` (a-set) or ``mgg`` (g-set). pyNastran is not used: version 1.4 does not import with
numpy >= 2.4.

Frames
------
``phg`` is in each grid's output (CD) coordinate system. The rigid-body modes of
:func:`pyyeti.nastran.n2p.rbgeom_uset` about the basic origin read :math:`T_g^T` in the
translation–translation block of grid g, :math:`T_g` being the rotation from the grid's output
system to basic at the grid (rectangular, cylindrical or spherical); shapes are rotated to basic
with it. Scalar and extra points (e.g. the modal coordinates of upstream superelements) and
q-set grids are generalised coordinates, not nodes: they are not in ``shapes`` but they are in
the mass partition, so the rigid mass and the participation are exact.

Mass properties
---------------
With R the rigid-body modes about ``reference`` on the mass partition (a-set with ``maa``, else
g-set with ``mgg``) and Φ the shapes on it,

.. math::

    M_{rr} = \tfrac12 (R^T M R + (R^T M R)^T), \qquad L = \Phi^T M R.

Units
-----
NASTRAN is unit-free: give the model's consistent units as ``units`` (pint strings for
``length``, ``mass`` and ``time``; with PARAM,WTMASS the mass unit is that of the scaled mass
matrix). With :math:`s = \sqrt{m_u}\,(1, 1, 1, \ell_u, \ell_u, \ell_u)` (kg and m per model unit)
shapes are divided by s, rigid mass and participation multiplied by it on both sides / columns,
lengths by :math:`\ell_u` and frequencies divided by the seconds per model time unit.
"""

from __future__ import annotations

import errno
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_finite, require_nonneg
from flexsat.structures.io_op2 import read_op2_modes
from flexsat.structures.modal_import import SI_UNITS, eigen_frequencies, unit_scales
from flexsat.structures.modal_model import RIGID_FREQUENCY, ModalModel
from flexsat.units import FloatArray

__all__ = ["SI_UNITS", "read_nastran_modes"]

_MISSING_PYYETI = (
    "read_nastran_modes needs the optional dependency pyyeti: pip install 'flexsat[nastran]'"
)
_RANK_TOL = 1e-6  # relative singular value below which a rigid motion is absent from the model


def read_nastran_modes(
    op2_path: str | Path,
    op4_path: str | Path | None = None,
    superelement: int = 0,
    damping: npt.ArrayLike = 0.0,
    reference: npt.ArrayLike = (0.0, 0.0, 0.0),
    units: Mapping[str, str] | None = None,
    rigid_frequency: float = RIGID_FREQUENCY,
) -> ModalModel:
    r"""Modal model of one superelement of a NAS2CAM OP2/OP4 pair, or of a plain SOL 103 OP2.

    Without ``op4_path`` and without an ``.op4`` beside the OP2, the OP2 is read as the output
    of a plain SOL 103 run by :func:`flexsat.structures.io_op2.read_op2_modes` (no pyyeti
    needed; a cantilevered model then needs that function's ``participation``).

    Parameters
    ----------
    op2_path : str or path
        The ``.op2`` file written by NAS2CAM.
    op4_path : str or path, optional
        The matching ``.op4`` file; default ``op2_path`` with the suffix ``.op4`` if it exists,
        else none (plain SOL 103 OP2).
    superelement : int
        Superelement id (0 is the residual).
    damping : float or array_like (m,)
        Modal damping ratios ζ (NASTRAN modes carry none).
    reference : array_like (3,)
        Point of the rigid-body modes in basic coordinates, in model length units.
    units : mapping, optional
        Pint unit strings of the model's ``"length"``, ``"mass"`` and ``"time"``; default SI
        (:data:`SI_UNITS`).
    rigid_frequency : float
        Modes at or below this ω, rad/s, are rigid-body modes; their eigen-solver roundoff
        (which pyyeti makes positive) is set to 0.

    Returns
    -------
    ModalModel
        In SI. Frequencies :math:`\sqrt{\max(\lambda, 0)}`, the rigid-body modes set to 0;
        boundary "free" when the number of rigid-body modes equals the number of rigid motions
        the model has, "cantilevered" when there are none.

    Raises
    ------
    ImportError
        pyyeti is not installed.
    FileNotFoundError
        The OP2 or OP4 file does not exist (named in the message).
    FieldError
        A plain OP2: as :func:`flexsat.structures.io_op2.read_op2_modes`, and ``superelement``
        other than 0.
    ValueError
        The superelement is not in the file; eigenvalues, g-set shapes or a mass matrix are
        missing (named); sizes disagree; the frequencies are not ascending once the rigid-body
        modes are 0; the model is partially constrained; bad ``units``.
    """
    if op4_path is None and not Path(op2_path).with_suffix(".op4").is_file():
        if superelement != 0:
            raise FieldError(
                "superelement",
                f"a plain SOL 103 OP2 (no OP4 beside it) holds superelement 0, got {superelement}",
            )
        return read_op2_modes(
            op2_path,
            damping=damping,
            reference=reference,
            units=units,
            rigid_frequency=rigid_frequency,
        )
    # pyyeti's n2p sets numpy's legacy "1.13" print options when first imported (a module-level
    # set_printoptions): the user's printing must not change because a model was read
    options = np.get_printoptions()
    try:
        from pyyeti.nastran import n2p, op2
    except ImportError as exc:
        raise ImportError(_MISSING_PYYETI) from exc
    finally:
        np.set_printoptions(**options)
    op2_file, op4_file = _paths(op2_path, op4_path)
    length, mass_unit, time = unit_scales(units)
    nas = op2.rdnas2cam(str(op2_file), str(op4_file))
    source = f"{op2_file.name}/{op4_file.name}"
    _check_modal_data(nas, superelement, source)
    uset = nas["uset"][superelement]
    lam, phg = np.ravel(nas["lambda"][superelement]), nas["phg"][superelement]
    mass, rows = _mass_partition(nas, superelement, n2p.mksetpv(uset, "g", "a"))
    _check_sizes(lam, phg, uset, mass, rows, source)

    ref = require_finite(reference, "reference")
    if ref.shape != (3,):
        raise FieldError("reference", f"must have shape (3,), got {ref.shape}")
    R = n2p.rbgeom_uset(uset, ref)[rows]
    ids, xyz, first, T = _grids(uset, n2p.rbgeom_uset(uset))
    s = np.sqrt(mass_unit) * np.array([1.0, 1.0, 1.0, length, length, length])
    rigid_mass, participation = _mass_properties(mass, R, phg[rows])
    rigid_w = float(require_nonneg(rigid_frequency, "rigid_frequency"))
    frequencies = eigen_frequencies(lam, time, rigid_w)
    return ModalModel(
        node_ids=ids,
        coordinates=xyz * length,
        frequencies=frequencies,
        damping=require_nonneg(damping, "damping"),  # a scalar or one per mode
        shapes=_basic_shapes(phg, first, T) / s,
        rigid_mass=rigid_mass * np.outer(s, s),
        participation=participation * s,
        reference=ref * length,
        boundary=_boundary(frequencies, rigid_mass, source),
    )


def _paths(op2_path: str | Path, op4_path: str | Path | None) -> tuple[Path, Path]:
    """The OP2 and OP4 paths, both existing."""
    op2_file = Path(op2_path)
    op4_file = op2_file.with_suffix(".op4") if op4_path is None else Path(op4_path)
    for kind, path in (("OP2", op2_file), ("OP4", op4_file)):
        if not path.is_file():
            raise FileNotFoundError(errno.ENOENT, f"NASTRAN {kind} file not found", str(path))
    return op2_file, op4_file


def _check_modal_data(nas: dict[str, Any], se: int, source: str) -> None:
    """The superelement exists and has eigenvalues, g-set shapes and a mass matrix."""
    if se not in nas["uset"]:
        known = sorted(int(k) for k in nas["uset"])  # ints: a numpy 2 scalar shows np.int32(…)
        raise FieldError("superelement", f"{se!r} is not in {source} (superelements {known})")
    missing = [
        label
        for key, label in (("lambda", "eigenvalues LAMBDA"), ("phg", "g-set mode shapes PHG"))
        if se not in nas.get(key, {})
    ]
    if not any(se in nas.get(key, {}) for key in ("maa", "mgg")):
        missing.append("mass matrix MAA or MGG")
    if missing:
        raise ValueError(
            f"{source}: no modal data for superelement {se}: missing {', '.join(missing)}"
        )


def _mass_partition(
    nas: dict[str, Any], se: int, aset: npt.NDArray[np.bool_]
) -> tuple[FloatArray, npt.NDArray[np.bool_]]:
    """Mass matrix and the g-set rows it acts on: MAA on the a-set if present, else MGG."""
    if se in nas.get("maa", {}):
        return nas["maa"][se], aset
    return nas["mgg"][se], np.ones(aset.size, dtype=bool)


def _check_sizes(
    lam: FloatArray,
    phg: FloatArray,
    uset: Any,
    mass: FloatArray,
    rows: npt.NDArray[np.bool_],
    source: str,
) -> None:
    if phg.shape != (len(uset), lam.size):
        raise ValueError(
            f"{source}: PHG has shape {phg.shape}, expected (g-set size, modes) = "
            f"{(len(uset), lam.size)}"
        )
    if mass.shape != (rows.sum(),) * 2:
        raise ValueError(
            f"{source}: mass matrix has shape {mass.shape}, expected {(rows.sum(),) * 2}"
        )


def _grids(
    uset: Any, rb_basic: FloatArray
) -> tuple[npt.NDArray[np.int64], FloatArray, npt.NDArray[np.intp], FloatArray]:
    """Grid ids, basic locations, g-set row of their dof 1 and output-to-basic rotations.

    ``rb_basic`` are the rigid-body modes about the basic origin; their translation block at a
    grid is the transpose of the rotation. Rows where it vanishes (scalar and extra points,
    q-set grids) are generalised coordinates and skipped.
    """
    first = np.flatnonzero(uset.index.get_level_values("dof") == 1)
    T = np.stack([rb_basic[i : i + 3, :3].T for i in first])
    grid = np.abs(np.linalg.det(T)) > 0.5
    first, T = first[grid], T[grid]
    ids = np.asarray(uset.index.get_level_values("id")[first], dtype=np.int64)
    return ids, uset.iloc[first][["x", "y", "z"]].to_numpy(dtype=float), first, T


def _basic_shapes(phg: FloatArray, first: npt.NDArray[np.intp], T: FloatArray) -> FloatArray:
    """Shapes (m, n, 6) in basic from the g-set shapes in the grids' output systems."""
    local = np.stack([phg[i : i + 6] for i in first])  # (n, 6, m)
    trans = np.einsum("nij,njm->mni", T, local[:, :3])
    rot = np.einsum("nij,njm->mni", T, local[:, 3:])
    return np.concatenate([trans, rot], axis=2)


def _mass_properties(
    mass: FloatArray, R: FloatArray, phi: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Symmetrised Rᵀ M R and Φᵀ M R on the mass partition (model units)."""
    MR = mass @ R
    rigid = R.T @ MR
    return 0.5 * (rigid + rigid.T), phi.T @ MR


def _boundary(frequencies: FloatArray, rigid_mass: FloatArray, source: str) -> str:
    """Free with one rigid-body mode per rigid motion the model has, cantilevered with none."""
    n_rigid = int(np.count_nonzero(frequencies == 0.0))
    if n_rigid == 0:
        return "cantilevered"
    d = np.sqrt(np.diag(rigid_mass))
    d = np.where(d > 0, d, 1.0)
    motions = np.linalg.matrix_rank(rigid_mass / np.outer(d, d), tol=_RANK_TOL)
    if n_rigid != motions:
        raise ValueError(
            f"{source}: {n_rigid} rigid-body modes for {motions} rigid motions: a partially "
            "constrained model is neither free nor cantilevered"
        )
    return "free"
