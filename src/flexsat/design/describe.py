"""What a design *is*, beside what it scores: the structure's modes and the controller's gains
and closed-loop poles of a design point, for a report to set the starting design beside the
final one (issue 23, deliverable 7).

A reference problem (the protocol of :class:`flexsat.design.pareto.BicriteriaReference`:
``responses(x)`` and ``problem()``) may also define

.. code-block:: python

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]: ...

returning named features of the design ``x`` (SI): each a real or complex array with its unit,
the discipline it belongs to (``"structure"`` or ``"control"``), labels of its elements and a
note saying how it was computed. The method is optional: :func:`describe_design` returns an
empty mapping for a problem without it, and refuses by name a ``describe`` that returns
anything but :class:`DesignFeature` values. :meth:`DesignFeature.as_data` is the plain
(JSON-ready) form a report stores: complex values as their real and imaginary parts.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["DISCIPLINES", "Describable", "DesignFeature", "describe_design", "sorted_poles"]

#: the disciplines a feature belongs to, in report order
DISCIPLINES = ("structure", "control")


@dataclass(frozen=True)
class DesignFeature:
    """One described property of a design point.

    Attributes
    ----------
    discipline : {"structure", "control"}
    values : (k,) float or complex ndarray
        SI (a scalar is stored as one element).
    unit : str
        Unit of the values ("" dimensionless or mixed, then ``note`` says).
    labels : tuple of str
        One label per element (default ``"1"``, ``"2"``, ...).
    note : str
        How it was computed (shown beside it).
    """

    discipline: Literal["structure", "control"]
    values: npt.NDArray[Any]
    unit: str = ""
    labels: tuple[str, ...] = field(default=())
    note: str = ""

    def __post_init__(self) -> None:
        if self.discipline not in DISCIPLINES:
            raise FieldError("discipline", f"must be one of {DISCIPLINES}, got {self.discipline!r}")
        values = np.atleast_1d(np.asarray(self.values))
        if values.ndim != 1 or values.dtype.kind not in "iufc":
            raise FieldError("values", f"must be a 1-D real or complex array, got {self.values!r}")
        if not np.all(np.isfinite(values)):
            raise FieldError("values", f"must be finite, got {values}")
        values = values.astype(complex if values.dtype.kind == "c" else float)
        labels = self.labels or tuple(str(i + 1) for i in range(values.size))
        if len(labels) != values.size:
            raise FieldError("labels", f"need one per value ({values.size}), got {len(labels)}")
        object.__setattr__(self, "values", values)
        object.__setattr__(self, "labels", tuple(str(s) for s in labels))

    @property
    def is_complex(self) -> bool:
        return bool(self.values.dtype.kind == "c")

    def as_data(self) -> dict[str, Any]:
        """Plain data: discipline, unit, labels, note and the values (complex ones as
        ``real`` and ``imag`` lists)."""
        out: dict[str, Any] = {
            "discipline": self.discipline,
            "unit": self.unit,
            "labels": list(self.labels),
            "note": self.note,
        }
        if self.is_complex:
            out["real"] = [float(v) for v in self.values.real]
            out["imag"] = [float(v) for v in self.values.imag]
        else:
            out["values"] = [float(v) for v in self.values]
        return out


@runtime_checkable
class Describable(Protocol):
    """A reference problem that can describe its designs (module docstring)."""

    def describe(self, x: FloatArray) -> Mapping[str, DesignFeature]: ...


def describe_design(reference: object, x: npt.ArrayLike) -> dict[str, DesignFeature]:
    """The features of the design ``x`` of ``reference``: its ``describe(x)``, or ``{}`` when it
    has none (the method is optional).

    Raises
    ------
    FieldError
        ``describe`` of the reference returned something other than a mapping of str to
        :class:`DesignFeature`.
    """
    if not isinstance(reference, Describable):
        return {}
    out = reference.describe(np.asarray(x, dtype=float))
    name = type(reference).__name__
    if not isinstance(out, Mapping):
        raise FieldError(f"{name}.describe", f"must return a mapping, got {type(out).__name__}")
    for key, feature in out.items():
        if not isinstance(key, str) or not isinstance(feature, DesignFeature):
            raise FieldError(
                f"{name}.describe",
                f"must map names (str) to DesignFeature, got {key!r}: {type(feature).__name__}",
            )
    return dict(out)


def sorted_poles(poles: npt.ArrayLike) -> npt.NDArray[np.complex128]:
    """Poles in a fixed order: by |imaginary part|, then real part, then the sign of the
    imaginary part (a conjugate pair adjacent, positive first), so that two designs' poles
    can be set side by side."""
    p = np.asarray(poles, dtype=complex).ravel()
    order = np.lexsort((-np.sign(p.imag), p.real, np.round(np.abs(p.imag), 12)))
    return p[order]
