r"""Test data shared by real and synthetic tests: time histories or FRFs with channel metadata.

A :class:`Measurement` holds either

* time histories (``domain="time"``): ``outputs`` (q, N) and, when recorded, ``inputs`` (r, N)
  on a uniform time axis in seconds; or
* frequency response functions (``domain="frequency"``): ``outputs`` (q, r, N) complex, output
  channel over input channel, on a frequency axis in Hz; ``inputs`` is then ``None`` and
  ``input_channels`` name the references.

Every channel is a :class:`~flexsat.dynamics.plant.Channel` located on the structure
(:meth:`Channel.at <flexsat.dynamics.plant.Channel.at>`): what it measures (``kind``), where
(``node``, ``direction``) and in which ``unit``. Universal-file dataset 58 import/export goes
through pyuff (:func:`flexsat.structures.io_uff.read_uff`): one function per channel (time
response, type 1) or per output/input pair (FRF, type 4), with response/reference node and
direction.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np
import numpy.typing as npt

from flexsat.dynamics.plant import AXES, STRUCTURAL_KINDS, Channel
from flexsat.input_checks import FieldError, require_finite
from flexsat.units import FloatArray

if TYPE_CHECKING:
    import xarray

__all__ = ["STRUCTURAL_KINDS", "Channel", "Measurement", "uff_direction"]

ComplexArray: TypeAlias = npt.NDArray[np.complex128]

_ROTATIONAL = ("rotation", "strain", "torque")
#: UFF dataset 58 ordinate specific data types (8 displacement, 11 velocity, 12 acceleration,
#: 3 strain, 13 excitation force); rotation and torque are 8 and 13 on a rotational dof.
_UFF_SPEC = {
    "displacement": 8,
    "velocity": 11,
    "acceleration": 12,
    "rotation": 8,
    "strain": 3,
    "force": 13,
    "torque": 13,
}
_UFF_KIND = {
    (8, False): "displacement",
    (8, True): "rotation",
    (11, False): "velocity",
    (12, False): "acceleration",
    (3, True): "strain",
    (3, False): "strain",
    (13, False): "force",
    (13, True): "torque",
}


def uff_direction(channel: Channel) -> int:
    """UFF dof code of a located channel: 1..3 translation x, y, z, 4..6 rotation about x, y,
    z."""
    return AXES.index(channel.direction) + (4 if channel.kind in _ROTATIONAL else 1)


def _uff_spec(channel: Channel) -> int:
    """UFF ordinate specific data type of a located channel."""
    assert channel.kind is not None  # a Measurement keeps located channels only (__post_init__)
    return _UFF_SPEC[channel.kind]


def _channels(value: Iterable[object], field: str) -> tuple[Channel, ...]:
    items = tuple(value)
    channels = []
    for i, c in enumerate(items):
        if not isinstance(c, Channel) or c.kind is None:
            raise FieldError(
                f"{field}[{i}]",
                f"must be a Channel located on the structure (Channel.at), got {c!r}",
            )
        channels.append(c)
    return tuple(channels)


def _data(value: npt.ArrayLike, field: str, complex_ok: bool) -> FloatArray | ComplexArray:
    try:
        arr = np.array(value, dtype=complex if complex_ok else float)
    except (TypeError, ValueError):
        raise FieldError(field, f"must be a numeric array, got {type(value).__name__}") from None
    if not np.all(np.isfinite(arr)):
        bad = int(np.sum(~np.isfinite(arr)))
        raise FieldError(field, f"must be finite (no NaN or inf), got {bad} non-finite entries")
    return arr


@dataclass(frozen=True, eq=False)
class Measurement:
    """Time histories or FRFs with channel metadata (see the module docstring).

    Parameters
    ----------
    abscissa : array_like (N,)
        Time, s (uniform, ascending) or frequency, Hz (ascending).
    outputs : array_like
        (q, N) time histories or (q, r, N) complex FRFs.
    output_channels : sequence of Channel, length q
    inputs : array_like (r, N), optional
        Recorded inputs of a time-domain test.
    input_channels : sequence of Channel, length r
    domain : {"time", "frequency"}

    Raises
    ------
    ValueError
        Naming the field: NaN/inf data, shapes that do not match the channels or the abscissa,
        a non-uniform time axis.
    """

    abscissa: FloatArray
    outputs: FloatArray | ComplexArray
    output_channels: tuple[Channel, ...] = ()
    inputs: FloatArray | None = None
    input_channels: tuple[Channel, ...] = ()
    domain: str = "time"
    attrs: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.domain not in ("time", "frequency"):
            raise FieldError("domain", f"must be 'time' or 'frequency', got {self.domain!r}")
        x = require_finite(self.abscissa, "abscissa")
        if x.ndim != 1 or x.size < 2 or np.any(np.diff(x) <= 0):
            raise FieldError("abscissa", "must be a 1-D ascending array of at least 2 values")
        if self.domain == "time":
            dt = np.diff(x)
            if np.ptp(dt) > 1e-6 * dt.mean():
                raise FieldError("abscissa", "time samples must be uniformly spaced")
        freq = self.domain == "frequency"
        outs = _data(self.outputs, "outputs", complex_ok=freq)
        ochan = _channels(self.output_channels, "output_channels")
        ichan = _channels(self.input_channels, "input_channels")
        n = x.size
        if freq:
            want = (len(ochan), len(ichan), n)
            if outs.shape != want:
                raise FieldError(
                    "outputs",
                    "FRFs must have shape (outputs, inputs, frequencies) "
                    f"= {want}, got {outs.shape}",
                )
            if self.inputs is not None:
                raise FieldError("inputs", "must be None for FRF data (the FRF is per unit input)")
            ins = None
        else:
            if outs.shape != (len(ochan), n):
                raise FieldError(
                    "outputs",
                    "must have shape (output_channels, samples) = "
                    f"{(len(ochan), n)}, got {outs.shape}",
                )
            ins = None
            if self.inputs is not None:
                ins = _data(self.inputs, "inputs", complex_ok=False)
                if ins.shape != (len(ichan), n):
                    raise FieldError(
                        "inputs",
                        "must have shape (input_channels, samples) = "
                        f"{(len(ichan), n)}, got {ins.shape}",
                    )
        object.__setattr__(self, "abscissa", x)
        object.__setattr__(self, "outputs", outs)
        object.__setattr__(self, "inputs", ins)
        object.__setattr__(self, "output_channels", ochan)
        object.__setattr__(self, "input_channels", ichan)

    # ------------------------------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Sample interval, s (time domain)."""
        return float(np.mean(np.diff(self.abscissa)))

    @property
    def sample_rate(self) -> float:
        """Samples per second, Hz (time domain)."""
        return 1.0 / self.dt

    def __repr__(self) -> str:
        return (
            f"Measurement(domain={self.domain!r}, outputs={len(self.output_channels)}, "
            f"inputs={len(self.input_channels)}, samples={self.abscissa.size})"
        )

    def to_dataset(self) -> xarray.Dataset:
        """xarray.Dataset: ``outputs`` (and ``inputs``) with per-channel coordinates."""
        import xarray as xr

        dim = self.domain
        coords: dict[str, tuple[Any, ...]] = {
            dim: (dim, self.abscissa, {"units": "s" if dim == "time" else "Hz"})
        }
        for prefix, chans in (("output", self.output_channels), ("input", self.input_channels)):
            for attr in ("kind", "node", "direction", "unit", "name"):
                values = [getattr(c, attr) for c in chans]
                coords[f"{prefix}_{attr}"] = (f"{prefix}_channel", values)
            coords[f"{prefix}_node_a"] = (
                f"{prefix}_channel",
                [-1 if c.node_a is None else c.node_a for c in chans],
            )
        data: dict[str, tuple[tuple[str, ...], FloatArray | ComplexArray]]
        if dim == "time":
            data = {"outputs": (("output_channel", dim), self.outputs)}
            if self.inputs is not None:
                data["inputs"] = (("input_channel", dim), self.inputs)
        else:
            data = {"outputs": (("output_channel", "input_channel", dim), self.outputs)}
        return xr.Dataset(data, coords=coords, attrs=dict(self.attrs))

    # ------------------------------------------------------------------------------------------
    # universal file 58
    def to_uff(self, path: str | Path) -> None:
        """Write as universal-file datasets 58 (one per channel, or per FRF pair), SI units.

        Time histories: function type 1 (time response), outputs then inputs (reference node 0
        for inputs). FRFs: function type 4, reference = the input channel. A strain channel's
        ``node_a`` is kept in ID line 2 (``"node_a <id>"``).
        """
        from flexsat.structures.io_uff import require_pyuff

        pyuff = require_pyuff("Measurement.to_uff")
        x = self.abscissa
        common = dict(
            abscissa_spacing=1,
            abscissa_min=float(x[0]),
            abscissa_inc=float((x[-1] - x[0]) / (x.size - 1)),
            num_pts=x.size,
            abscissa_spec_data_type=17 if self.domain == "time" else 18,
            abscissa_axis_units_lab="s" if self.domain == "time" else "Hz",
            x=x,
            load_case_id=0,
            ver_num=0,
            rsp_ent_name="flexsat",
            ref_ent_name="flexsat",
            z_axis_value=0.0,
            id3="NONE",
            id4="NONE",
            id5="NONE",
        )

        def one(
            chan: Channel,
            data: FloatArray | ComplexArray,
            ref: Channel | None,
            func_type: int,
            ord_type: int,
        ) -> dict[str, Any]:
            ref_node, ref_dir, den_units, den_spec = (
                (0, 0, "NONE", 0)
                if ref is None
                else (ref.node, uff_direction(ref), ref.unit, _uff_spec(ref))
            )
            return pyuff.prepare_58(
                id1=chan.name,
                id2=f"node_a {chan.node_a}" if chan.node_a is not None else "NONE",
                func_type=func_type,
                rsp_node=chan.node,
                rsp_dir=uff_direction(chan),
                ref_node=ref_node,
                ref_dir=ref_dir,
                ord_data_type=ord_type,
                data=data,
                ordinate_spec_data_type=_uff_spec(chan),
                ordinate_axis_units_lab=chan.unit,
                orddenom_spec_data_type=den_spec,
                orddenom_axis_units_lab=den_units,
                **common,
            )

        sets = []
        if self.domain == "time":
            for c, d in zip(self.output_channels, self.outputs):
                sets.append(one(c, d, None, 1, 4))
            if self.inputs is not None:
                for c, d in zip(self.input_channels, self.inputs):
                    sets.append(one(c, d, None, 1, 4))
        else:
            for i, c in enumerate(self.output_channels):
                for j, ref in enumerate(self.input_channels):
                    sets.append(one(c, self.outputs[i, j], ref, 4, 6))
        pyuff.UFF(str(Path(path))).write_sets(sets, mode="overwrite")

    @classmethod
    def from_uff(cls, path: str | Path) -> Measurement:
        """Read dataset-58 functions written by :meth:`to_uff` or by test software.

        Time histories (function type 1): channels of kind force/torque (excitation, specific
        data type 13) become ``inputs``, the others ``outputs``. FRFs (type 4): grouped by
        response and reference into (q, r, N). Channel kind comes from the ordinate specific
        data type and the dof code; units are the file's labels.

        Raises
        ------
        ValueError
            No dataset 58, mixed function types or abscissae, or incomplete FRF sets.
        """
        from flexsat.structures.io_uff import read_uff

        functions = read_uff(path).get(58, [])
        if not functions:
            raise ValueError(f"{path}: no function data (dataset 58)")
        x = np.asarray(functions[0]["x"], dtype=float)
        types = {int(f["func_type"]) for f in functions}
        if len(types) != 1 or types.pop() not in (1, 4):
            raise ValueError(f"{path}: functions must be all time responses (1) or all FRFs (4)")
        for f in functions:
            if np.asarray(f["x"]).shape != x.shape or not np.allclose(f["x"], x, rtol=1e-9):
                raise ValueError(f"{path}: functions have different abscissae")
        frf = int(functions[0]["func_type"]) == 4

        def channel(
            node: Any, code: Any, spec: Any, units: Any, name: Any = "", id2: Any = ""
        ) -> Channel:
            code = abs(int(code))
            rot = code >= 4
            kind = _UFF_KIND.get((int(spec), rot), "rotation" if rot else "displacement")
            node_a = None
            text = str(id2).strip()
            if text.startswith("node_a "):
                node_a = int(text.split()[1])
            if kind == "strain" and node_a is None:
                node_a = int(node)
            units = str(units).strip()
            return Channel.at(
                kind,
                int(node),
                AXES[(code - 1) % 3],
                None if units in ("", "NONE") else units,
                node_a,
                str(name).strip() if str(name).strip() not in ("", "NONE") else "",
            )

        if not frf:
            outs: list[FloatArray] = []
            ins: list[FloatArray] = []
            ochan: list[Channel] = []
            ichan: list[Channel] = []
            for f in functions:
                c = channel(
                    f["rsp_node"],
                    f["rsp_dir"],
                    f.get("ordinate_spec_data_type", 0),
                    f.get("ordinate_axis_units_lab", ""),
                    f.get("id1", ""),
                    f.get("id2", ""),
                )
                (ins if c.kind in ("force", "torque") else outs).append(np.real(f["data"]))
                (ichan if c.kind in ("force", "torque") else ochan).append(c)
            return cls(
                x,
                np.array(outs).reshape(len(outs), x.size),
                tuple(ochan),
                np.array(ins) if ins else None,
                tuple(ichan) if ins else (),
                "time",
            )
        ochan, ichan = [], []
        table: dict[tuple[int, int], ComplexArray] = {}
        for f in functions:
            c = channel(
                f["rsp_node"],
                f["rsp_dir"],
                f.get("ordinate_spec_data_type", 0),
                f.get("ordinate_axis_units_lab", ""),
                f.get("id1", ""),
                f.get("id2", ""),
            )
            r = channel(
                f["ref_node"],
                f["ref_dir"],
                f.get("orddenom_spec_data_type", 13),
                f.get("orddenom_axis_units_lab", ""),
            )
            if c not in ochan:
                ochan.append(c)
            if r not in ichan:
                ichan.append(r)
            table[(ochan.index(c), ichan.index(r))] = np.asarray(f["data"], dtype=complex)
        if len(table) != len(ochan) * len(ichan):
            raise ValueError(f"{path}: FRFs missing for some response/reference pairs")
        data = np.array([[table[(i, j)] for j in range(len(ichan))] for i in range(len(ochan))])
        return cls(x, data, tuple(ochan), None, tuple(ichan), "frequency")
