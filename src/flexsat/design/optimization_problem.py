r"""A design-optimisation problem as data: variables, an objective and constraints.

Convention (minimisation, the one every optimiser here is driven in)::

    minimise f(x)  subject to  g_i(x) <= 0 (inequality),  h_j(x) = 0 (equality),
                               lower_k <= x_k <= upper_k (bounds)

Each response (objective or constraint) is a callable of the design vector x (SI floats, in the
order of the variables). With ``gradient="analytic"`` it returns ``(value, gradient)``, the
gradient a (n,) array of ∂value/∂x_k in SI units; with ``gradient="central"`` it returns the
value only and the gradient is taken by central differences, step
h_k = ``step`` · max(|x_k|, scale_k), truncation O(h²) (the caller asks for this by name: there
is no silent fallback from an analytic gradient to differences).

Scaling: the optimisers see z_k = x_k / scale_k, f / scale_f and g_i / scale_i (the responses'
``scale``), so that a well-chosen scale makes every variable and response of order one; the
KKT residuals of :mod:`flexsat.design.kkt` are measured in these scaled units.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = [
    "GRADIENT_KINDS",
    "CONSTRAINT_KINDS",
    "Constraint",
    "DesignProblem",
    "DesignVariable",
    "Evaluation",
    "Objective",
]

GRADIENT_KINDS = ("analytic", "central")
CONSTRAINT_KINDS = ("inequality", "equality")


def _finite_positive(value: object, field_name: str) -> float:
    try:
        out = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise FieldError(field_name, f"must be a number, got {value!r}") from None
    if not (np.isfinite(out) and out > 0):
        raise FieldError(field_name, f"must be finite and > 0, got {value!r}")
    return out


def _name(value: object, field_name: str) -> str:
    if not isinstance(value, str) or not value.strip():
        raise FieldError(field_name, f"must be a non-empty string, got {value!r}")
    return value


@dataclass(frozen=True)
class DesignVariable:
    """One continuous design variable.

    Attributes
    ----------
    name : str
    value : float
        Starting value, SI, within the bounds.
    lower, upper : float
        Bounds, SI (``-inf`` / ``inf`` for none); lower < upper.
    scale : float
        Typical magnitude: the optimisers see value / scale. Default: |value| (1 if 0).
    unit : str
        SI unit of the value, for reports ("m", "kg", "" for a ratio).
    """

    name: str
    value: float
    lower: float = -np.inf
    upper: float = np.inf
    scale: float | None = None
    unit: str = ""

    def __post_init__(self) -> None:
        name = _name(self.name, "name")
        where = f"variables[{name!r}]"
        try:
            value, lower, upper = float(self.value), float(self.lower), float(self.upper)
        except (TypeError, ValueError):
            raise FieldError(where, "value, lower and upper must be numbers") from None
        if not np.isfinite(value):
            raise FieldError(f"{where}.value", f"must be finite, got {self.value!r}")
        if np.isnan(lower) or np.isnan(upper) or not lower < upper:
            raise FieldError(f"{where}.lower", f"must be < upper, got [{lower}, {upper}]")
        if not lower <= value <= upper:
            raise FieldError(f"{where}.value", f"{value} is outside [{lower}, {upper}]")
        scale = (abs(value) or 1.0) if self.scale is None else self.scale
        if not isinstance(self.unit, str):
            raise FieldError(f"{where}.unit", f"must be a string, got {self.unit!r}")
        object.__setattr__(self, "value", value)
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)
        object.__setattr__(self, "scale", _finite_positive(scale, f"{where}.scale"))


@dataclass(frozen=True)
class Objective:
    """The function minimised.

    Attributes
    ----------
    name : str
    function : callable
        ``function(x) -> (value, gradient)`` when ``gradient == "analytic"``, else
        ``function(x) -> value``.
    gradient : {"analytic", "central"}
    step : float
        Relative central-difference step (used only with ``gradient="central"``).
    scale : float
        Typical magnitude of the value (the optimisers see value / scale).
    unit : str
    """

    name: str
    function: Callable[[FloatArray], object]
    gradient: str = "analytic"
    step: float = 1e-6
    scale: float = 1.0
    unit: str = ""

    def __post_init__(self) -> None:
        _check_response(self, "objective")


@dataclass(frozen=True)
class Constraint:
    """A constraint g(x) <= 0 (``kind="inequality"``) or h(x) = 0 (``kind="equality"``).

    Attributes as :class:`Objective`, plus ``kind``. Write g >= b as b − g <= 0.
    """

    name: str
    function: Callable[[FloatArray], object]
    kind: str = "inequality"
    gradient: str = "analytic"
    step: float = 1e-6
    scale: float = 1.0
    unit: str = ""

    def __post_init__(self) -> None:
        _check_response(self, f"constraints[{self.name!r}]")
        if self.kind not in CONSTRAINT_KINDS:
            raise FieldError(
                f"constraints[{self.name!r}].kind",
                f"must be one of {CONSTRAINT_KINDS} (g <= 0 or h = 0), got {self.kind!r}",
            )


def _check_response(resp: Objective | Constraint, where: str) -> None:
    _name(resp.name, f"{where}.name")
    if not callable(resp.function):
        raise FieldError(f"{where}.function", f"must be callable, got {resp.function!r}")
    if resp.gradient not in GRADIENT_KINDS:
        raise FieldError(
            f"{where}.gradient", f"must be one of {GRADIENT_KINDS}, got {resp.gradient!r}"
        )
    object.__setattr__(resp, "step", _finite_positive(resp.step, f"{where}.step"))
    object.__setattr__(resp, "scale", _finite_positive(resp.scale, f"{where}.scale"))


@dataclass(frozen=True)
class Evaluation:
    """Responses at one design point, SI (unscaled).

    Attributes
    ----------
    x : (n,) design vector
    objective : float;  objective_gradient : (n,)
    constraints : (m,) g_i or h_j in the order of the problem's constraints
    constraint_jacobian : (m, n)
    """

    x: FloatArray
    objective: float
    objective_gradient: FloatArray
    constraints: FloatArray
    constraint_jacobian: FloatArray


@dataclass(frozen=True)
class DesignProblem:
    """Variables, objective and constraints (see the module notes for the convention).

    The last evaluated point is cached, so that an optimiser asking for the value, the
    gradient and the constraints at one x calls each response once.
    """

    variables: tuple[DesignVariable, ...]
    objective: Objective
    constraints: tuple[Constraint, ...] = ()
    _cache: dict[bytes, Evaluation] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )
    _count: list[int] = field(default_factory=lambda: [0], init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        variables = _sequence(self.variables, "variables", DesignVariable)
        if not variables:
            raise FieldError("variables", "must hold at least one DesignVariable")
        names = [v.name for v in variables]
        if len(set(names)) != len(names):
            raise FieldError("variables", f"names must be distinct, got {names}")
        if not isinstance(self.objective, Objective):
            raise FieldError(
                "objective", f"must be an Objective, got {type(self.objective).__name__}"
            )
        constraints = _sequence(self.constraints, "constraints", Constraint)
        cnames = [c.name for c in constraints]
        if len(set(cnames)) != len(cnames):
            raise FieldError("constraints", f"names must be distinct, got {cnames}")
        object.__setattr__(self, "variables", variables)
        object.__setattr__(self, "constraints", constraints)

    # -- vectors of the variables ----------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables)

    @property
    def x0(self) -> FloatArray:
        return np.array([v.value for v in self.variables])

    @property
    def lower(self) -> FloatArray:
        return np.array([v.lower for v in self.variables])

    @property
    def upper(self) -> FloatArray:
        return np.array([v.upper for v in self.variables])

    @property
    def scale(self) -> FloatArray:
        return np.array([float(v.scale) for v in self.variables])  # type: ignore[arg-type]

    @property
    def constraint_scale(self) -> FloatArray:
        return np.array([c.scale for c in self.constraints])

    @property
    def equality(self) -> npt.NDArray[np.bool_]:
        """True for each equality constraint, False for each inequality."""
        return np.array([c.kind == "equality" for c in self.constraints], dtype=bool)

    def start(self, x0: npt.ArrayLike | None = None) -> FloatArray:
        """The starting design: ``x0`` (checked: length, finite, within bounds) or the values."""
        if x0 is None:
            return self.x0
        x = np.asarray(x0, dtype=float).reshape(-1)
        if x.size != len(self.variables):
            raise FieldError("x0", f"must have {len(self.variables)} entries, got {x.size}")
        if not np.all(np.isfinite(x)):
            raise FieldError("x0", f"must be finite, got {x}")
        outside = (x < self.lower) | (x > self.upper)
        if outside.any():
            k = int(np.flatnonzero(outside)[0])
            raise FieldError("x0", f"{self.names[k]} = {x[k]} is outside its bounds")
        return x

    # -- evaluation ------------------------------------------------------------------------
    @property
    def evaluations(self) -> int:
        """Points evaluated so far (each calls every response once; cached repeats not counted)."""
        return self._count[0]

    def evaluate(self, x: npt.ArrayLike) -> Evaluation:
        """Objective, constraints and their gradients at x (SI), each response called once."""
        xv = np.array(x, dtype=float).reshape(-1)
        if xv.size != len(self.variables):
            raise FieldError("x", f"must have {len(self.variables)} entries, got {xv.size}")
        key = xv.tobytes()
        if key in self._cache:
            return self._cache[key]
        f, df = self._response(self.objective, xv, "objective")
        m = len(self.constraints)
        g, dg = np.zeros(m), np.zeros((m, xv.size))
        for i, c in enumerate(self.constraints):
            g[i], dg[i] = self._response(c, xv, f"constraints[{c.name!r}]")
        out = Evaluation(xv, f, df, g, dg)
        self._count[0] += 1
        self._cache.clear()
        self._cache[key] = out
        return out

    def _response(
        self, resp: Objective | Constraint, x: FloatArray, where: str
    ) -> tuple[float, FloatArray]:
        if resp.gradient == "analytic":
            out = resp.function(x.copy())
            if not (isinstance(out, tuple) and len(out) == 2):
                raise FieldError(
                    f"{where}.function",
                    "with gradient='analytic' must return (value, gradient); ask for "
                    "gradient='central' to difference a value-only function",
                )
            value, grad = _value(out[0], where), np.asarray(out[1], dtype=float).reshape(-1)
            if grad.size != x.size or not np.all(np.isfinite(grad)):
                raise FieldError(
                    f"{where}.function",
                    f"gradient must be {x.size} finite numbers, got {out[1]!r}",
                )
            return value, grad
        value = _value(resp.function(x.copy()), where)
        h = resp.step * np.maximum(np.abs(x), self.scale)
        grad = np.zeros(x.size)
        for k in range(x.size):
            e = np.zeros(x.size)
            e[k] = h[k]
            up = _value(resp.function(x + e), where)
            down = _value(resp.function(x - e), where)
            grad[k] = (up - down) / (2.0 * h[k])
        return value, grad


def _value(value: object, where: str) -> float:
    try:
        out = float(np.asarray(value, dtype=float).reshape(()))
    except (TypeError, ValueError):
        raise FieldError(f"{where}.function", f"must return a number, got {value!r}") from None
    if not np.isfinite(out):
        raise FieldError(f"{where}.function", f"returned a non-finite value {out}")
    return out


def _sequence(items: object, field_name: str, kind: type) -> tuple:
    if isinstance(items, kind):
        items = (items,)
    if isinstance(items, (str, bytes)) or not isinstance(items, Sequence):
        raise FieldError(field_name, f"must be a sequence of {kind.__name__}, got {items!r}")
    for item in items:
        if not isinstance(item, kind):
            raise FieldError(
                field_name, f"each must be a {kind.__name__}, got {type(item).__name__}"
            )
    return tuple(items)
