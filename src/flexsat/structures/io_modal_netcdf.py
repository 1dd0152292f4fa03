"""A :class:`~flexsat.structures.modal_model.ModalModel` as one netCDF-4 file with a unit on
every variable (written by :meth:`ModalModel.save`, read by :meth:`ModalModel.load`); the
format's version is :data:`~flexsat.structures.modal_model.FORMAT_VERSION`."""

from __future__ import annotations

import numpy as np
import xarray as xr

from flexsat.input_checks import FieldError
from flexsat.structures.modal_model import FORMAT_VERSION, ModalModel

__all__ = ["NETCDF_ENCODING", "UNITS", "modal_model_dataset", "modal_model_from_dataset"]

#: the unit of every variable of the file (one unit per variable: shapes split by block)
UNITS = {
    "coordinates": "m",
    "frequencies": "rad/s",
    "damping": "1",
    "translation_shapes": "kg**-0.5",
    "rotation_shapes": "kg**-0.5/m",
    "mass_tt": "kg",
    "mass_tr": "kg*m",
    "mass_rt": "kg*m",
    "mass_rr": "kg*m**2",
    "participation_translation": "kg**0.5",
    "participation_rotation": "kg**0.5*m",
    "reference": "m",
}
#: no fill value on any variable: a modal model has no missing entries
NETCDF_ENCODING = {name: {"_FillValue": None} for name in UNITS}


def modal_model_dataset(model: ModalModel) -> xr.Dataset:
    """The netCDF layout of :meth:`ModalModel.save` (its docstring lists the variables)."""
    Mr, S, P = model.rigid_mass, model.shapes, model.participation
    data = {
        "coordinates": (("node", "axis"), model.coordinates),
        "frequencies": (("mode",), model.frequencies),
        "damping": (("mode",), model.damping),
        "translation_shapes": (("mode", "node", "axis"), S[..., :3]),
        "rotation_shapes": (("mode", "node", "axis"), S[..., 3:]),
        "mass_tt": (("axis", "axis_j"), Mr[:3, :3]),
        "mass_tr": (("axis", "axis_j"), Mr[:3, 3:]),
        "mass_rt": (("axis", "axis_j"), Mr[3:, :3]),
        "mass_rr": (("axis", "axis_j"), Mr[3:, 3:]),
        "participation_translation": (("mode", "axis"), P[:, :3]),
        "participation_rotation": (("mode", "axis"), P[:, 3:]),
        "reference": (("axis",), model.reference),
    }
    variables = {k: (dims, np.array(v), {"units": UNITS[k]}) for k, (dims, v) in data.items()}
    return xr.Dataset(
        variables,
        coords={"node": ("node", model.node_ids, {"units": "1", "long_name": "node id"})},
        attrs={
            "flexsat_modal_model_version": FORMAT_VERSION,
            "boundary": model.boundary,
            "title": "flexsat modal model",
            "axis": "x y z (global)",
        },
    )


def modal_model_from_dataset(ds: xr.Dataset) -> ModalModel:
    """A :class:`ModalModel` from :func:`modal_model_dataset`'s layout, validated like any
    construction; a dataset of another kind or version is refused, naming ``path``."""
    version = ds.attrs.get("flexsat_modal_model_version")
    if version is None:
        raise FieldError(
            "path", "not a flexsat modal model (no flexsat_modal_model_version attribute)"
        )
    if int(version) != FORMAT_VERSION:
        raise FieldError(
            "path", f"flexsat_modal_model_version {version} not supported (reads {FORMAT_VERSION})"
        )
    v = {name: ds[name].values for name in UNITS}
    return ModalModel(
        node_ids=ds["node"].values,
        coordinates=v["coordinates"],
        frequencies=v["frequencies"],
        damping=v["damping"],
        shapes=np.concatenate([v["translation_shapes"], v["rotation_shapes"]], axis=-1),
        rigid_mass=np.block([[v["mass_tt"], v["mass_tr"]], [v["mass_rt"], v["mass_rr"]]]),
        participation=np.concatenate(
            [v["participation_translation"], v["participation_rotation"]], axis=-1
        ),
        reference=v["reference"],
        boundary=str(ds.attrs["boundary"]),
    )
