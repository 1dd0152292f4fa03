r"""Universal files (UFF): nodes (15, 2411), modes (55), functions (58), through pyuff.

Reading and writing are done by the optional dependency pyuff (``pip install 'flexsat[uff]'``).

Units
-----
A units dataset 164 gives the factors that convert file units to SI (SI value = file value /
factor) for length :math:`f_L` and force :math:`f_F`; time is always seconds and the mass unit is
force s² / length, so one file mass unit is :math:`f_L / f_F` kg. Without a dataset 164 the file is
taken to be SI. :func:`write_modal_uff` writes SI with a dataset 164 saying so.

Modal models
------------
Dataset 55 holds, per normal mode, the frequency in Hz, the modal mass :math:`\mu = \phi^T M \phi`
and the viscous damping ratio, and the shape at nodes (3 or 6 values per node, in global axes).
Shapes are mass-normalised as :math:`\phi / \sqrt{\mu}` (``normalisation="modal_mass"``, the
default, refused when a modal mass is 0, i.e. unknown) or taken as already mass-normalised
(``normalisation="as_is"``).

A universal file has no mass matrix, so the rigid mass and the participation
:math:`L = \Phi^T M R` come from the six rigid-body modes of a free model
(:func:`flexsat.structures.modal_import.mass_properties_from_modes`, projected onto the
rigid-mass form since dataset 55 stores six significant digits). A model without rigid-body
modes (cantilevered) needs ``rigid_mass`` and ``participation`` from the caller.
"""

from __future__ import annotations

import errno
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError, require_finite, require_nonneg
from flexsat.structures.modal_import import mass_properties_from_modes
from flexsat.structures.modal_model import RIGID_FREQUENCY, ModalModel
from flexsat.units import FloatArray

__all__ = [
    "NORMALISATIONS",
    "modal_model_from_uff",
    "read_uff",
    "read_uff_functions",
    "write_modal_uff",
]

NORMALISATIONS = ("modal_mass", "as_is")

_ABSCISSA_NAMES = {17: "time", 18: "frequency"}  # dataset 58 specific data types

#: one dataset as pyuff reads it: field name -> value
UffDataset: TypeAlias = dict[str, Any]

if TYPE_CHECKING:
    import xarray


# ------------------------------------------------------------------------------------------------
# reading
def require_pyuff(caller: str) -> ModuleType:
    try:
        import pyuff
    except ImportError as exc:
        raise ImportError(
            f"{caller} needs the optional dependency pyuff: pip install 'flexsat[uff]'"
        ) from exc
    return pyuff


def _read(path: str | Path, caller: str) -> tuple[Path, dict[int, list[UffDataset]]]:
    pyuff = require_pyuff(caller)
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(errno.ENOENT, "universal file not found", str(path))
    uff = pyuff.UFF(str(path))
    if uff.get_n_sets() == 0:
        raise ValueError(f"{path}: no universal-file datasets (blocks delimited by '    -1')")
    datasets: dict[int, list[UffDataset]] = {}
    for i in range(uff.get_n_sets()):
        try:
            dset = uff.read_sets(i)
        except Exception as exc:  # pyuff raises bare Exception for malformed datasets
            raise ValueError(f"{path}: dataset {i + 1} cannot be read ({exc})") from exc
        datasets.setdefault(int(dset["type"]), []).append(dset)
    return path, datasets


def read_uff(path: str | Path) -> dict[int, list[UffDataset]]:
    """All datasets of a universal file, as read by pyuff.

    Parameters
    ----------
    path : str or path

    Returns
    -------
    dict
        Dataset type (e.g. 15, 55, 58, 164, 2411) -> list of pyuff dataset dictionaries in file
        order. Types pyuff does not read hold only ``{"type": ...}``.

    Raises
    ------
    ImportError
        pyuff is not installed.
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        No dataset in the file, or a dataset pyuff cannot parse.
    """
    return _read(path, "read_uff")[1]


def _unit_factors(datasets: dict[int, list[UffDataset]]) -> tuple[float, float]:
    """Metres and kilograms per file unit of length and mass (dataset 164, else SI)."""
    if 164 not in datasets:
        return 1.0, 1.0
    units = datasets[164][0]
    return 1.0 / units["length"], units["length"] / units["force"]


def _nodes(
    datasets: dict[int, list[UffDataset]], path: Path
) -> tuple[npt.NDArray[np.int64], FloatArray]:
    """Node ids and coordinates (file units) from datasets 2411 (preferred) or 15."""
    kind = 2411 if 2411 in datasets else 15
    if kind not in datasets:
        raise ValueError(f"{path}: no node coordinates (dataset 15 or 2411)")
    ids, xyz = [], []
    for d in datasets[kind]:
        if np.any(np.asarray(d["def_cs"]) != 0) or np.any(np.asarray(d["disp_cs"]) != 0):
            raise ValueError(
                f"{path}: dataset {kind} has nodes in local coordinate systems (def_cs/disp_cs != "
                "0); "
                "only global coordinates are supported"
            )
        ids.append(np.asarray(d["node_nums"], dtype=float).astype(np.int64))
        xyz.append(np.column_stack([d["x"], d["y"], d["z"]]).astype(float))
    return np.concatenate(ids), np.vstack(xyz)


def _normal_modes(datasets: dict[int, list[UffDataset]], path: Path) -> list[UffDataset]:
    """Real normal-mode datasets 55, in ascending frequency."""
    modes = [d for d in datasets.get(55, []) if d["analysis_type"] == 2]
    if not modes:
        raise ValueError(f"{path}: no modal data (dataset 55 with analysis type 2, normal modes)")
    if any(d["data_type"] != 2 for d in modes):
        raise ValueError(f"{path}: dataset 55 normal modes must be real (data type 2)")
    return sorted(modes, key=lambda d: d["freq"])


def _shapes(modes: list[UffDataset], node_ids: npt.NDArray[np.int64], path: Path) -> FloatArray:
    """(m, n, 6) shapes as stored; nodes a mode does not list read zero (UFF note 9)."""
    index = {int(nid): j for j, nid in enumerate(node_ids)}
    shapes = np.zeros((len(modes), node_ids.size, 6))
    for i, d in enumerate(modes):
        unknown = sorted(set(map(int, d["node_nums"])) - set(index))
        if unknown:
            raise ValueError(
                f"{path}: mode {d['mode_n']} has values at nodes {unknown[:8]} without coordinates"
            )
        rows = [index[int(nid)] for nid in d["node_nums"]]
        for k in range(d["n_data_per_node"]):
            shapes[i, rows, k] = d[f"r{k + 1}"]
    return shapes


def _normalised(
    shapes: FloatArray, modes: list[UffDataset], normalisation: str, path: Path
) -> FloatArray:
    if normalisation not in NORMALISATIONS:
        raise FieldError("normalisation", f"must be one of {NORMALISATIONS}, got {normalisation!r}")
    if normalisation == "as_is":
        return shapes
    mu = np.array([d["modal_m"] for d in modes], dtype=float)
    if np.any(mu <= 0):
        mode = modes[int(np.argmax(mu <= 0))]["mode_n"]
        raise ValueError(
            f"{path}: mode {mode} has no modal mass (dataset 55 record 8 field 2 is 0), so its "
            "shape "
            "cannot be mass-normalised; pass normalisation='as_is' if the shapes already are"
        )
    return shapes / np.sqrt(mu)[:, None, None]


def modal_model_from_uff(
    path: str | Path,
    damping: npt.ArrayLike | None = None,
    normalisation: str = "modal_mass",
    reference: npt.ArrayLike = (0.0, 0.0, 0.0),
    rigid_mass: npt.ArrayLike | None = None,
    participation: npt.ArrayLike | None = None,
    rigid_frequency: float = RIGID_FREQUENCY,
) -> ModalModel:
    """Modal model from the nodes (15 or 2411) and normal modes (55) of a universal file.

    Parameters
    ----------
    path : str or path
    damping : float or array_like (m,), optional
        Modal damping ratios; default the viscous damping ratios of the datasets 55.
    normalisation : {"modal_mass", "as_is"}
        Divide each shape by the square root of its modal mass, or take the shapes as
        mass-normalised (see the module docstring).
    reference : array_like (3,)
        Point of the rigid motion, m (SI, in the global axes of the nodes).
    rigid_mass, participation : array_like (6, 6) and (m, 6), optional
        SI, about ``reference``, modes in ascending frequency. Required when the file has no
        six rigid-body modes; otherwise derived from them.
    rigid_frequency : float
        Modes at or below this ω, rad/s, are rigid-body modes (ω set to 0).

    Returns
    -------
    ModalModel
        SI; "free" when the file has rigid-body modes, else "cantilevered".

    Raises
    ------
    ImportError, FileNotFoundError
        As :func:`read_uff`.
    ValueError
        No nodes or no normal modes (named), nodes in local systems, mode values at unknown
        nodes, complex modes, a zero modal mass with ``normalisation="modal_mass"``, rigid-body
        modes that are not rigid, or mass properties neither given nor derivable.
    """
    path, datasets = _read(path, "modal_model_from_uff")
    length, mass = _unit_factors(datasets)
    node_ids, xyz = _nodes(datasets, path)
    modes = _normal_modes(datasets, path)
    s = np.sqrt(mass) * np.array([1.0, 1.0, 1.0, length, length, length])
    shapes = _normalised(_shapes(modes, node_ids, path), modes, normalisation, path) / s
    w = 2 * np.pi * np.array([d["freq"] for d in modes], dtype=float)
    frequencies = np.where(w <= float(require_nonneg(rigid_frequency, "rigid_frequency")), 0.0, w)
    ref = require_finite(reference, "reference")
    if ref.shape != (3,):
        raise FieldError("reference", f"must have shape (3,), got {ref.shape}")
    rigid_mass, participation, boundary = mass_properties_from_modes(
        frequencies, shapes, xyz * length, ref, rigid_mass, participation, path, "a universal file"
    )
    return ModalModel(
        node_ids=node_ids,
        coordinates=xyz * length,
        frequencies=frequencies,
        damping=require_nonneg(
            [d["modal_damp_vis"] for d in modes] if damping is None else damping, "damping"
        ),
        shapes=shapes,
        rigid_mass=rigid_mass,
        participation=participation,
        reference=ref,
        boundary=boundary,
    )


def _label(value: object) -> str:
    """A dataset 58 label; pyuff's placeholder NONE reads as empty."""
    text = str(value).strip()
    return "" if text.upper() == "NONE" else text


def read_uff_functions(path: str | Path) -> xarray.Dataset:
    """Functions at nodal dofs (dataset 58: time histories, spectra, FRFs) as one xarray Dataset.

    Parameters
    ----------
    path : str or path

    Returns
    -------
    xarray.Dataset
        ``data`` (function, abscissa dim), real or complex. The abscissa dimension is "time"
        (specific data type 17), "frequency" (18) or "abscissa", with ``units`` and
        ``long_name`` from the file's labels. Per-function coordinates: ``function_type``
        (UFF code, e.g. 1 time response, 4 FRF), ``description`` (ID line 1),
        ``response_node``, ``response_direction``, ``reference_node``, ``reference_direction``
        (±1..±6 for ±x, y, z translation, ±rotation), ``ordinate_units``,
        ``denominator_units``. Units are the file's labels, not converted.

    Raises
    ------
    ImportError, FileNotFoundError
        As :func:`read_uff`.
    ValueError
        No dataset 58, or functions with different abscissae.
    """
    import xarray as xr

    path, datasets = _read(path, "read_uff_functions")
    functions = datasets.get(58, [])
    if not functions:
        raise ValueError(f"{path}: no function data (dataset 58)")
    first = functions[0]
    x = np.asarray(first["x"], dtype=float)
    for j, d in enumerate(functions[1:], start=2):
        other = np.asarray(d["x"], dtype=float)
        if other.shape != x.shape or not np.allclose(other, x, rtol=1e-9, atol=0.0):
            raise ValueError(
                f"{path}: dataset 58 functions 1 and {j} have different abscissae; read them one "
                "by one with read_uff"
            )
    dim = _ABSCISSA_NAMES.get(int(first["abscissa_spec_data_type"]), "abscissa")
    per_function: dict[str, tuple[str, Callable[[Any], int | str]]] = {
        "function_type": ("func_type", int),
        "description": ("id1", _label),
        "response_node": ("rsp_node", int),
        "response_direction": ("rsp_dir", int),
        "reference_node": ("ref_node", int),
        "reference_direction": ("ref_dir", int),
        "ordinate_units": ("ordinate_axis_units_lab", _label),
        "denominator_units": ("orddenom_axis_units_lab", _label),
    }
    coords: dict[str, tuple[Any, ...]] = {
        name: ("function", [convert(d[key]) for d in functions])
        for name, (key, convert) in per_function.items()
    }
    coords[dim] = (
        dim,
        x,
        {
            "units": _label(first["abscissa_axis_units_lab"]),
            "long_name": _label(first["abscissa_axis_lab"]),
        },
    )
    data = np.stack([np.asarray(d["data"]) for d in functions])
    return xr.Dataset(
        {"data": (("function", dim), data)}, coords=coords, attrs={"source": str(path)}
    )


# ------------------------------------------------------------------------------------------------
# writing
def write_modal_uff(model: ModalModel, path: str | Path) -> None:
    """Write a modal model as a universal file: units (164, SI), nodes (15), modes (55).

    Each mode is a dataset 55 (normal mode, 6 values per node in global axes) with its
    frequency in Hz, modal mass 1 (the shapes are mass-normalised) and viscous damping ratio.
    Datasets 15 and 55 store six significant digits. The rigid mass, the participation and the
    reference are not stored (no UFF dataset holds them): :func:`modal_model_from_uff` derives
    them again for a free model; pass them back for a cantilevered one.

    Parameters
    ----------
    model : ModalModel
    path : str or path
        Overwritten if it exists.

    Raises
    ------
    ImportError
        pyuff is not installed.
    """
    pyuff = require_pyuff("write_modal_uff")
    nodes, xyz = [int(n) for n in model.node_ids], model.coordinates
    datasets = [
        pyuff.prepare_164(
            units_code=1,
            units_description="SI",
            temp_mode=1,
            length=1.0,
            force=1.0,
            temp=1.0,
            temp_offset=273.15,
        ),
        pyuff.prepare_15(node_nums=nodes, x=xyz[:, 0], y=xyz[:, 1], z=xyz[:, 2]),
    ]
    for i in range(model.n_modes):
        values = {f"r{k + 1}": model.shapes[i, :, k] for k in range(6)}
        datasets.append(
            pyuff.prepare_55(
                id1="flexsat modal model",
                id2=f"boundary {model.boundary}",
                id3="NONE",
                id4=f"Mode {i + 1}",
                id5="NONE",
                model_type=1,
                analysis_type=2,
                data_ch=3,
                spec_data_type=8,
                data_type=2,
                n_data_per_node=6,
                node_nums=nodes,
                load_case=1,
                mode_n=i + 1,
                freq=float(model.frequencies_hz[i]),
                modal_m=1.0,
                modal_damp_vis=float(model.damping[i]),
                modal_damp_his=0.0,
                **values,
            )
        )
    pyuff.UFF(str(Path(path))).write_sets(datasets, mode="overwrite")
