r"""Parameter spaces of sweeps and Monte Carlo sets: named parameters with SI units, their grids,
space-filling sequences and distributions, and the table of N cases drawn from them (issue 13,
"Deliver" item 1).

A parameter is a scenario quantity (a hub inertia, a torque limit, a damping ratio) named by the
caller and declared in its SI unit (``"kg*m**2"``, ``"N*m"``, ``"rad"``, ``""`` for a
dimensionless one). Every value given for it (a mean, a bound, a grid value) is a float in that
unit, a pint Quantity or a unit string, converted with :func:`flexsat.units.to_si_array`, so
published values are entered as published: ``"300 ozf*in"`` for Junkins, Pollock &
Rahman 1990's torque limit (pint's
``oz`` is the ounce of mass; the ounce-force is ``ozf``), ``"5 deg"`` for an angle.

The pieces:

* :class:`GridAxis` and :class:`GridSpace` — a list or a linspace of values per parameter, the
  full factorial of the axes with the first axis varying slowest (C order, as
  :func:`itertools.product`), case ``k`` at the grid index ``np.unravel_index(k, shape)``;
* :class:`Normal`, :class:`Uniform`, :class:`LogNormal`, :class:`TruncatedNormal` — the
  distributions, each a map :math:`x = F^{-1}(u)` of a uniform :math:`u \in (0, 1)` through its
  inverse CDF (scipy.stats), so every sampler below draws uniforms and maps them;
* :class:`ParameterSpace` — independent distributions and their samplers: plain Monte Carlo
  (:meth:`~ParameterSpace.sample`), Latin hypercube and scrambled Sobol' sequences
  (scipy.stats.qmc), and the Saltelli design of Sobol' indices (SALib,
  :meth:`~ParameterSpace.sobol_design`; a :class:`Uniform` is the "bounds" of a sequence over a
  box), and the per-case seeds of the random processes inside a case
  (:meth:`~ParameterSpace.noise_seeds`);
* :class:`SampleTable` — the output: name → (N,) SI array, the units, the index of the first case;
* :func:`parameter_from_spec` / :func:`space_from_spec` — the same objects from the dicts of a
  YAML scenario, with field-path error messages.

**Lognormal convention.** :math:`\ln X \sim N(\ln m, (\ln g)^2)` with the median :math:`m > 0`
(in the parameter's unit) and the geometric standard deviation :math:`g > 1` (dimensionless):
:math:`m` is the nominal value and :math:`[m/g, m g]` holds 68 % of the cases, a factor
dispersion as stiffnesses and damping ratios are quoted ("known to a factor 1.5"). The mean is
:math:`m e^{(\ln g)^2/2}`.

**Truncated normal.** The parent normal's mean and sd and the bounds ``low < high``; either bound
may be infinite (one-sided: ``low: 0`` keeps an inertia positive), and the parent must put a
nonzero probability between them.

**Reproducibility and chunking.** Plain Monte Carlo draws case by case: parameter ``p`` has its
own PCG64 stream seeded by ``SeedSequence([seed, h(p)])`` with ``h`` the first 128 bits of the
SHA-256 of the name, and case ``i`` takes the ``i``-th 64-bit output of that stream as
:math:`u = (\lfloor r / 2^{11} \rfloor + 1/2)\, 2^{-53} \in (0, 1)` (PCG64 ``advance`` jumps to
it). A case's values therefore depend only on (seed, name, case index): any chunking of the case
range gives the same table, a run extended from N to 2N keeps its first N cases, and adding or
removing a parameter leaves the others' values unchanged. The Latin hypercube, Sobol' and
Saltelli designs are joint constructions over all N cases: they are generated whole from the
seed and a chunk is a slice of that table (:meth:`SampleTable.rows`). PCG64's output is stable
across numpy versions (NEP 19); the sequences' scrambling follows scipy's and SALib's generators,
so they reproduce for given scipy and SALib versions.

**Faces of the unit cube.** Scrambled sequences use finitely many bits, so a coordinate can be
exactly 0; :func:`_open_unit` moves such points in by :math:`2^{-53}` so that an unbounded
distribution maps them to a finite value (a shift far below any sampling resolution).

References: M. D. McKay, R. J. Beckman and W. J. Conover, Technometrics 21 (1979) 239–245 (Latin
hypercube); A. B. Owen, "Scrambling Sobol' and Niederreiter–Xing points", J. Complexity 14 (1998)
466–489; A. Saltelli et al., Comput. Phys. Commun. 181 (2010) 259–270 (the Sobol' design).
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from dataclasses import field as dataclass_field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from scipy import stats
from scipy.stats import qmc

from flexsat import limits
from flexsat.input_checks import FieldError, require_count
from flexsat.limits import check_count
from flexsat.units import (
    FloatArray,
    QuantityArrayLike,
    QuantityLike,
    parse_quantity,
    to_si_array,
)

#: the smallest step of a double in [0.5, 1): the margin kept from the faces of the unit cube
_UNIT_MARGIN = 2.0**-53


def _open_unit(u: FloatArray) -> FloatArray:
    """``u`` clipped into [2^-53, 1 - 2^-53] (see the module: faces of the unit cube)."""
    return np.clip(u, _UNIT_MARGIN, 1.0 - _UNIT_MARGIN)


def _check_name(name: object, field_path: str) -> str:
    if not isinstance(name, str) or not name.strip():
        raise FieldError(field_path, f"a parameter name must be a non-empty string, got {name!r}")
    return name


def require_si_unit(unit: object, field_path: str) -> str:
    """The parameter's unit must be its SI unit: the table holds SI values under that label."""
    if not isinstance(unit, str):
        raise FieldError(
            f"{field_path}.unit",
            f"must be a unit string such as 'N*m' or '' (dimensionless), got {unit!r}",
        )
    factor = parse_quantity(f"1 {unit}", f"{field_path}.unit").to_base_units().magnitude
    if factor != 1.0:
        raise FieldError(
            f"{field_path}.unit",
            "must be an SI unit (the table holds SI values); "
            f"1 {unit} is {factor:.6g} of its SI unit; declare the SI unit and give "
            f"values as strings such as '5 {unit}'",
        )
    return unit


def si_scalar(
    value: QuantityLike, unit: str, field_path: str, allow_infinite: bool = False
) -> float:
    """One SI number from a float in ``unit``, a Quantity or a unit string; finite unless
    ``allow_infinite`` (never NaN)."""
    arr = to_si_array(value, unit, field_path)
    if arr.size != 1:
        raise FieldError(field_path, f"must be a single number, got {value!r}")
    x = float(arr.reshape(()))
    if math.isnan(x) or (math.isinf(x) and not allow_infinite):
        raise FieldError(field_path, f"must be finite (no NaN or inf), got {value!r}")
    return x


class _Distribution:
    """The shared part of the distributions: ``name``, ``unit``, the frozen scipy distribution
    ``frozen`` and the inverse-CDF map :meth:`ppf`. ``field`` (default: the name) prefixes the
    error messages, e.g. ``parameters.hub_inertia`` for a scenario."""

    #: the spec name of the distribution (``distribution:`` in a scenario)
    kind: str = ""
    # declared by every distribution (dataclass fields of the subclasses)
    name: str
    unit: str
    field: str | None

    def _start(self) -> str:
        prefix = self.field or _check_name(self.name, "parameter")
        _check_name(self.name, prefix)
        object.__setattr__(self, "field", prefix)
        require_si_unit(self.unit, prefix)
        return prefix

    def _mean_sd(
        self, f: str, mean_given: QuantityLike, sd_given: QuantityLike
    ) -> tuple[float, float]:
        """(mean, sd) in SI of a normal's parameters: mean finite, sd > 0."""
        mean = si_scalar(mean_given, self.unit, f"{f}.mean")
        sd = si_scalar(sd_given, self.unit, f"{f}.sd")
        if sd <= 0:
            raise FieldError(f"{f}.sd", f"must be > 0 (a standard deviation), got {sd_given!r}")
        return mean, sd

    def _set(self, attr: str, value: float) -> None:
        object.__setattr__(self, attr, value)

    @property
    def frozen(self) -> Any:
        """The frozen ``scipy.stats`` distribution."""
        raise NotImplementedError

    def ppf(self, u: npt.ArrayLike) -> FloatArray:
        """The SI values :math:`x = F^{-1}(u)` at uniforms ``u`` in (0, 1)."""
        return np.asarray(self.frozen.ppf(u), dtype=float)


@dataclass(frozen=True)
class Normal(_Distribution):
    """:math:`X \\sim N(\\mu, \\sigma^2)`: ``mean`` μ finite, ``sd`` σ > 0 (both in ``unit``)."""

    name: str
    mean: float
    sd: float
    unit: str = ""
    field: str | None = dataclass_field(default=None, repr=False, compare=False)
    kind = "normal"

    if TYPE_CHECKING:  # the constructor takes quantities; the fields hold SI floats

        def __init__(
            self,
            name: str,
            mean: QuantityLike,
            sd: QuantityLike,
            unit: str = ...,
            field: str | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        f = self._start()
        mean, sd = self._mean_sd(f, self.mean, self.sd)
        self._set("mean", mean)
        self._set("sd", sd)

    @property
    def frozen(self) -> Any:
        return stats.norm(loc=self.mean, scale=self.sd)


@dataclass(frozen=True)
class Uniform(_Distribution):
    """:math:`X \\sim U(a, b)` with finite ``low`` a < ``high`` b (in ``unit``); the bounds of a
    Latin hypercube or Sobol' sequence over a box."""

    name: str
    low: float
    high: float
    unit: str = ""
    field: str | None = dataclass_field(default=None, repr=False, compare=False)
    kind = "uniform"

    if TYPE_CHECKING:  # the constructor takes quantities; the fields hold SI floats

        def __init__(
            self,
            name: str,
            low: QuantityLike,
            high: QuantityLike,
            unit: str = ...,
            field: str | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        f = self._start()
        low = si_scalar(self.low, self.unit, f"{f}.low")
        high = si_scalar(self.high, self.unit, f"{f}.high")
        if not low < high:
            raise FieldError(f, f"low must be < high, got low={self.low!r}, high={self.high!r}")
        self._set("low", low)
        self._set("high", high)

    @property
    def frozen(self) -> Any:
        return stats.uniform(loc=self.low, scale=self.high - self.low)


@dataclass(frozen=True)
class LogNormal(_Distribution):
    """:math:`\\ln X \\sim N(\\ln m, (\\ln g)^2)`: ``median`` m > 0 (in ``unit``), geometric
    standard deviation ``gsd`` g > 1 (dimensionless); see the module for the convention."""

    name: str
    median: float
    gsd: float
    unit: str = ""
    field: str | None = dataclass_field(default=None, repr=False, compare=False)
    kind = "lognormal"

    if TYPE_CHECKING:  # the constructor takes quantities; the fields hold SI floats

        def __init__(
            self,
            name: str,
            median: QuantityLike,
            gsd: QuantityLike,
            unit: str = ...,
            field: str | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        f = self._start()
        median = si_scalar(self.median, self.unit, f"{f}.median")
        if median <= 0:
            raise FieldError(
                f"{f}.median",
                f"must be > 0 (a lognormal variable is positive), got {self.median!r}",
            )
        gsd = si_scalar(self.gsd, "", f"{f}.gsd")
        if gsd <= 1:
            raise FieldError(
                f"{f}.gsd",
                "the geometric standard deviation must be > 1 "
                f"(dimensionless; 1.1 is a 10 % dispersion), got {self.gsd!r}",
            )
        self._set("median", median)
        self._set("gsd", gsd)

    @property
    def frozen(self) -> Any:
        return stats.lognorm(s=math.log(self.gsd), scale=self.median)


@dataclass(frozen=True)
class TruncatedNormal(_Distribution):
    """The normal N(``mean``, ``sd``²) restricted to [``low``, ``high``] (scipy.stats.truncnorm):
    mean finite, sd > 0, low < high, either bound may be infinite, and the parent normal must put
    a nonzero probability between the bounds."""

    name: str
    mean: float
    sd: float
    low: float
    high: float
    unit: str = ""
    field: str | None = dataclass_field(default=None, repr=False, compare=False)
    kind = "truncated_normal"

    if TYPE_CHECKING:  # the constructor takes quantities; the fields hold SI floats

        def __init__(
            self,
            name: str,
            mean: QuantityLike,
            sd: QuantityLike,
            low: QuantityLike,
            high: QuantityLike,
            unit: str = ...,
            field: str | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        f = self._start()
        mean, sd = self._mean_sd(f, self.mean, self.sd)
        low = si_scalar(self.low, self.unit, f"{f}.low", allow_infinite=True)
        high = si_scalar(self.high, self.unit, f"{f}.high", allow_infinite=True)
        if not low < high:
            raise FieldError(f, f"low must be < high, got low={self.low!r}, high={self.high!r}")
        a, b = (low - mean) / sd, (high - mean) / sd
        # the probability of [a, b] under N(0, 1), from the tail nearer to the interval so that
        # far tails do not cancel to 0 in 1 - Phi
        mass = (
            (stats.norm.sf(a) - stats.norm.sf(b))
            if a > 0
            else (stats.norm.cdf(b) - stats.norm.cdf(a))
        )
        if not mass > 0:
            raise FieldError(
                f,
                f"the normal N({mean:g}, {sd:g}²) puts no probability in "
                f"[{low:g}, {high:g}] ({a:.3g} to {b:.3g} sd from the mean)",
            )
        for attr, v in (("mean", mean), ("sd", sd), ("low", low), ("high", high)):
            self._set(attr, v)

    @property
    def frozen(self) -> Any:
        return stats.truncnorm(
            (self.low - self.mean) / self.sd,
            (self.high - self.mean) / self.sd,
            loc=self.mean,
            scale=self.sd,
        )

    def ppf(self, u: npt.ArrayLike) -> FloatArray:
        # loc + scale z can round one ulp past a bound; the clip keeps the stated support exactly
        return np.clip(super().ppf(u), self.low, self.high)


#: the distributions by their spec name, with the keys each takes (in constructor order)
DISTRIBUTIONS: dict[str, tuple[type, tuple[str, ...]]] = {
    "normal": (Normal, ("mean", "sd")),
    "uniform": (Uniform, ("low", "high")),
    "lognormal": (LogNormal, ("median", "gsd")),
    "truncated_normal": (TruncatedNormal, ("mean", "sd", "low", "high")),
}

Distribution = Normal | Uniform | LogNormal | TruncatedNormal


@dataclass(frozen=True)
class SampleTable:
    """N cases: ``values`` name → (N,) SI array, ``units`` name → SI unit, ``start`` the index of
    the first case in the whole run (nonzero for a chunk)."""

    values: dict[str, FloatArray]
    units: dict[str, str]
    start: int = 0

    def __len__(self) -> int:
        return len(next(iter(self.values.values()))) if self.values else 0

    @property
    def names(self) -> list[str]:
        return list(self.values)

    def matrix(self) -> FloatArray:
        """The (N, d) array of the values, columns in :attr:`names` order."""
        return np.column_stack([self.values[n] for n in self.names])

    def rows(self, start: int, stop: int) -> SampleTable:
        """Cases ``start`` to ``stop`` (indices of this table) as a table: a chunk."""
        return SampleTable(
            {k: v[start:stop] for k, v in self.values.items()}, dict(self.units), self.start + start
        )

    def case(self, i: int) -> dict[str, float]:
        """Case ``i`` (index of this table) as name → SI float."""
        return {k: float(v[i]) for k, v in self.values.items()}


@dataclass(frozen=True, eq=False)
class GridAxis:
    """One parameter's grid values (in ``unit``; any order, finite, at least one). Build a
    linspace with :meth:`linspace`."""

    name: str
    values: FloatArray
    unit: str = ""
    field: str | None = dataclass_field(default=None, repr=False, compare=False)

    if TYPE_CHECKING:  # the constructor takes quantities; ``values`` holds an SI float array

        def __init__(
            self,
            name: str,
            values: QuantityArrayLike,
            unit: str = ...,
            field: str | None = ...,
        ) -> None: ...

    def __post_init__(self) -> None:
        f = self.field or _check_name(self.name, "parameter")
        _check_name(self.name, f)
        object.__setattr__(self, "field", f)
        require_si_unit(self.unit, f)
        if isinstance(self.values, str):
            raise FieldError(
                f"{f}.values", f"must be a list of values, got the string {self.values!r}"
            )
        arr = to_si_array(self.values, self.unit, f"{f}.values")
        if arr.ndim != 1 or arr.size == 0:
            raise FieldError(
                f"{f}.values", f"must be a non-empty list of numbers, got shape {arr.shape}"
            )
        if not np.all(np.isfinite(arr)):
            raise FieldError(f"{f}.values", f"must be finite (no NaN or inf), got {self.values!r}")
        object.__setattr__(self, "values", arr)

    @classmethod
    def linspace(
        cls,
        name: str,
        low: QuantityLike,
        high: QuantityLike,
        n: int,
        unit: str = "",
        field: str | None = None,
    ) -> GridAxis:
        """``n`` ≥ 2 evenly spaced values from ``low`` to ``high`` (> ``low``), both included."""
        f = field or _check_name(name, "parameter")
        require_si_unit(unit, f)
        lo = si_scalar(low, unit, f"{f}.low")
        hi = si_scalar(high, unit, f"{f}.high")
        if not lo < hi:
            raise FieldError(f, f"low must be < high, got low={low!r}, high={high!r}")
        count = require_count(n, f"{f}.n")
        check_count(count, limits.MAX_CASES, f"{f}.n", "grid points on one axis")
        if count < 2:
            raise FieldError(
                f"{f}.n", f"a linspace needs n >= 2 (give one value as values: [x]), got {n!r}"
            )
        return cls(name, np.linspace(lo, hi, count), unit, field=f)


def _unique_names(items, field_path: str) -> None:
    seen = set()
    for item in items:
        if item.name in seen:
            raise FieldError(field_path, f"the parameter {item.name!r} is given twice")
        seen.add(item.name)


class GridSpace:
    """The full factorial of its axes, the first axis varying slowest (C order).

    Parameters
    ----------
    axes : sequence of GridAxis
        At least one, names unique.
    """

    def __init__(self, axes: Sequence[GridAxis], field_path: str = "parameters") -> None:
        axes = list(axes)
        if not axes or not all(isinstance(a, GridAxis) for a in axes):
            raise FieldError(field_path, f"a grid needs one GridAxis or more, got {axes!r}")
        _unique_names(axes, field_path)
        self.axes = axes

    @property
    def names(self) -> list[str]:
        return [a.name for a in self.axes]

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(a.values.size for a in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def table(self) -> SampleTable:
        """All ``size`` cases; case k is at grid index ``np.unravel_index(k, shape)``."""
        mesh = np.meshgrid(*[a.values for a in self.axes], indexing="ij")
        return SampleTable(
            {a.name: m.ravel() for a, m in zip(self.axes, mesh)},
            {a.name: a.unit for a in self.axes},
        )


def _seed(seed, field_path: str) -> int:
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise FieldError(field_path, f"the seed must be a non-negative integer, got {seed!r}")
    return int(seed)


def _start(start) -> int:
    if isinstance(start, bool) or not isinstance(start, (int, np.integer)) or start < 0:
        raise FieldError("start", f"must be a non-negative integer, got {start!r}")
    return int(start)


@dataclass(frozen=True)
class SobolDesign:
    """The Saltelli sample of a Sobol' analysis: ``table`` (``n_base`` (d + 2) cases, or
    ``n_base`` (2 d + 2) with second-order indices) in SALib's row order, and SALib's ``problem``
    (the unit cube: the analysis is invariant under the per-parameter inverse-CDF maps)."""

    table: SampleTable
    problem: dict[str, Any]
    n_base: int
    second_order: bool


class ParameterSpace:
    """Independent distributions over named parameters and their samplers (see the module).

    Parameters
    ----------
    parameters : sequence of Normal, Uniform, LogNormal or TruncatedNormal
        At least one, names unique.
    """

    def __init__(self, parameters: Sequence[Distribution], field_path: str = "parameters") -> None:
        parameters = list(parameters)
        if not parameters or not all(isinstance(p, _Distribution) for p in parameters):
            raise FieldError(
                field_path,
                "a parameter space needs one distribution or more "
                f"(Normal, Uniform, LogNormal, TruncatedNormal), got {parameters!r}",
            )
        _unique_names(parameters, field_path)
        self.parameters = parameters

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def units(self) -> dict[str, str]:
        return {p.name: p.unit for p in self.parameters}

    def from_unit(self, u: FloatArray, start: int = 0) -> SampleTable:
        """The table of points ``u`` (N, d) of the unit cube, column j mapped by parameter j's
        inverse CDF."""
        u = _open_unit(np.asarray(u, dtype=float))
        return SampleTable(
            {p.name: p.ppf(u[:, j]) for j, p in enumerate(self.parameters)}, self.units, start
        )

    @staticmethod
    def stream(name: str, seed: int, purpose: int = 0) -> np.random.PCG64:
        """Parameter ``name``'s PCG64 stream for ``seed`` (see the module); ``purpose`` 1 is the
        stream of the noise seeds (:meth:`noise_seeds`), apart from every parameter's."""
        digest = int.from_bytes(hashlib.sha256(name.encode()).digest()[:16], "little")
        words = [seed, digest] if purpose == 0 else [seed, digest, purpose]
        return np.random.PCG64(np.random.SeedSequence(words))

    @classmethod
    def noise_seeds(
        cls, n: int, seed: int, start: int = 0, name: str = "noise"
    ) -> npt.NDArray[np.uint64]:
        """Per-case seeds (uint64) of the random processes inside a case (sensor noise,
        disturbances), cases ``start`` to ``start + n``: the ``i``-th 64-bit output of the
        stream of (seed, ``name``), like a parameter's uniforms, so they too are independent of
        the chunking; seed a case's generator with ``np.random.default_rng(noise_seeds[i])``.
        Several processes take several names."""
        count = require_count(n, "n")
        bits = cls.stream(name, _seed(seed, "seed"), purpose=1)
        bits.advance(_start(start))
        return bits.random_raw(count)

    def sample(self, n: int, seed: int, start: int = 0) -> SampleTable:
        """Plain Monte Carlo: cases ``start`` to ``start + n`` of the run seeded by ``seed``, each
        case's values a function of (seed, name, case index) only."""
        count = require_count(n, "n")
        seed = _seed(seed, "seed")
        start = _start(start)
        columns = []
        for p in self.parameters:
            bits = self.stream(p.name, seed)
            bits.advance(start)
            raw = bits.random_raw(count)
            columns.append(((raw >> np.uint64(11)).astype(float) + 0.5) * 2.0**-53)
        return self.from_unit(np.column_stack(columns), int(start))

    def latin_hypercube(self, n: int, seed: int) -> SampleTable:
        """``n`` cases of a scrambled Latin hypercube (scipy.stats.qmc.LatinHypercube): each
        parameter's n equal-probability strata hold one case each."""
        count = require_count(n, "n")
        engine = qmc.LatinHypercube(len(self.parameters), rng=_seed(seed, "seed"))
        return self.from_unit(engine.random(count))

    def sobol_sequence(self, n: int, seed: int) -> SampleTable:
        """The first ``n`` (a power of 2, for the sequence's balance) points of a scrambled
        Sobol' sequence (scipy.stats.qmc.Sobol, Owen scrambling)."""
        count = require_count(n, "n")
        if count & (count - 1):
            raise FieldError(
                "n",
                "a Sobol' sequence needs a power of 2 (its balance holds on "
                f"2^m points), got {n!r}",
            )
        engine = qmc.Sobol(len(self.parameters), scramble=True, rng=_seed(seed, "seed"))
        return self.from_unit(engine.random_base2(int(math.log2(count))))

    def salib_problem(self) -> dict[str, Any]:
        """SALib's problem over the unit cube of this space."""
        return {
            "num_vars": len(self.parameters),
            "names": self.names,
            "bounds": [[0.0, 1.0]] * len(self.parameters),
        }

    def sobol_design(self, n_base: int, seed: int, second_order: bool = False) -> SobolDesign:
        """The Saltelli design for Sobol' indices (SALib.sample.sobol, scrambled): ``n_base`` (a
        power of 2) base points, ``n_base (d + 2)`` cases (``n_base (2 d + 2)`` with second-order
        indices); analyse with :func:`flexsat.design.monte_carlo_statistics.sobol_indices`."""
        from SALib.sample import sobol as salib_sobol

        count = require_count(n_base, "n_base")
        if count & (count - 1):
            raise FieldError("n_base", f"the Saltelli design needs a power of 2, got {n_base!r}")
        problem = self.salib_problem()
        u = salib_sobol.sample(
            problem,
            count,
            calc_second_order=bool(second_order),
            scramble=True,
            seed=_seed(seed, "seed"),
        )
        return SobolDesign(self.from_unit(u), problem, count, bool(second_order))


# -- scenario dicts --------------------------------------------------------------------------------
def _keys(
    spec: Mapping, allowed: tuple[str, ...], required: tuple[str, ...], field_path: str, what: str
) -> None:
    for key in spec:
        if key not in allowed:
            raise FieldError(
                f"{field_path}.{key}", f"unknown key; {what} takes {', '.join(allowed)}"
            )
    for key in required:
        if key not in spec:
            raise FieldError(f"{field_path}.{key}", f"missing; {what} takes {', '.join(allowed)}")


def parameter_from_spec(
    name: str, spec: Mapping, unit: str, field_path: str | None = None
) -> Distribution | GridAxis:
    """One parameter from its scenario dict, in the SI ``unit`` of the scenario field it sets.

    ``{distribution: normal, mean:, sd:}`` (also ``uniform`` low/high, ``lognormal``
    median/gsd, ``truncated_normal`` mean/sd/low/high) → the distribution; ``{values: [...]}`` →
    a :class:`GridAxis`; ``{low:, high:, n:}`` → a linspace axis; ``{low:, high:}`` → a
    :class:`Uniform` (the bounds of a Latin hypercube or Sobol' sequence). Values are numbers in
    ``unit`` or unit strings. Errors name ``field_path`` (default: the name) and the key.
    """
    f = field_path or name
    if not isinstance(spec, Mapping):
        raise FieldError(
            f,
            f"must be a mapping such as {{distribution: normal, mean: ..., "
            f"sd: ...}}, {{values: [...]}} or {{low: ..., high: ..., n: ...}}, "
            f"got {spec!r}",
        )
    if "distribution" in spec:
        kind = spec["distribution"]
        if kind not in DISTRIBUTIONS:
            raise FieldError(
                f"{f}.distribution",
                f"unknown distribution {kind!r}; known: {', '.join(DISTRIBUTIONS)}",
            )
        cls, keys = DISTRIBUTIONS[kind]
        _keys(spec, ("distribution", *keys), keys, f, f"a {kind} distribution")
        return cls(name, *(spec[k] for k in keys), unit=unit, field=f)
    if "values" in spec:
        _keys(spec, ("values",), ("values",), f, "a list of grid values")
        return GridAxis(name, spec["values"], unit, field=f)
    if "n" in spec:
        _keys(spec, ("low", "high", "n"), ("low", "high", "n"), f, "a linspace")
        return GridAxis.linspace(name, spec["low"], spec["high"], spec["n"], unit, field=f)
    if "low" in spec or "high" in spec:
        _keys(spec, ("low", "high"), ("low", "high"), f, "a range (uniform bounds)")
        return Uniform(name, spec["low"], spec["high"], unit, field=f)
    raise FieldError(
        f,
        f"give a distribution ({', '.join(DISTRIBUTIONS)}), values: [...], "
        f"low/high/n (a linspace) or low/high (bounds); got keys {sorted(spec)}",
    )


def space_from_spec(
    spec: Mapping, units: Mapping[str, str], field_path: str = "parameters"
) -> ParameterSpace | GridSpace:
    """The space of a scenario's ``parameters:`` dict (name → parameter dict).

    ``units`` maps every parameter the scenario can vary to its SI unit; a name outside it is
    refused. Grid axes make a :class:`GridSpace`, distributions a :class:`ParameterSpace`; the
    two do not mix (a grid is a design, a distribution a population).
    """
    if not isinstance(spec, Mapping) or not spec:
        raise FieldError(
            field_path,
            "must be a non-empty mapping of parameter name to its "
            f"values or distribution, got {spec!r}",
        )
    items = []
    for name, entry in spec.items():
        f = f"{field_path}.{name}"
        if name not in units:
            known = ", ".join(sorted(units)) or "none"
            raise FieldError(f, f"unknown parameter; known: {known}")
        items.append(parameter_from_spec(name, entry, units[name], f))
    grids = [isinstance(i, GridAxis) for i in items]
    if all(grids):
        return GridSpace([i for i in items if isinstance(i, GridAxis)], field_path)
    if not any(grids):
        return ParameterSpace([i for i in items if not isinstance(i, GridAxis)], field_path)
    odd = items[grids.index(not grids[0])]
    raise FieldError(
        f"{odd.field}",
        "grid axes (values, low/high/n) and distributions or bounds cannot be mixed in one space",
    )


__all__ = [
    "DISTRIBUTIONS",
    "GridAxis",
    "GridSpace",
    "LogNormal",
    "Normal",
    "ParameterSpace",
    "SampleTable",
    "SobolDesign",
    "TruncatedNormal",
    "Uniform",
    "parameter_from_spec",
    "require_si_unit",
    "si_scalar",
    "space_from_spec",
]
