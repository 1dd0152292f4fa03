r"""Statistics of a Monte Carlo set or a sweep: the probability of meeting each requirement with its
confidence interval, the percentiles of every metric, the convergence of these estimates with the
number of cases, and the global sensitivity of a metric to the parameters (issue 13, "Deliver"
item 1).

The inputs are plain arrays: a metric is an (N,) SI array over the cases (NaN where the case
produced no value), the parameters a :class:`~flexsat.design.parameter_space.SampleTable`.

**Requirements and missing values.** A :class:`Requirement` is ``metric <= threshold`` or
``metric >= threshold``. A NaN metric fails every requirement: NaN means the run produced no
value (a response that never settled, a diverged simulation), and a missing value never proves a
requirement met; it still counts among the N cases, so the probability is that of the whole
population. A producer whose missing value has a natural worst value (a settling time that never
comes) may report it as ``inf``, which then fails a ``<=`` and meets a ``>=`` as arithmetic says.

**Probability and its interval.** With :math:`k` of :math:`N` cases meeting the requirement the
estimate is :math:`\hat p = k/N`, and the default interval is Clopper and Pearson's (Biometrika
26 (1934) 404–413), the quantiles of beta distributions

.. math::

    p_L = B^{-1}\!\left(\tfrac{\alpha}{2};\, k,\, N - k + 1\right), \qquad
    p_U = B^{-1}\!\left(1 - \tfrac{\alpha}{2};\, k + 1,\, N - k\right),

with :math:`p_L = 0` at :math:`k = 0` and :math:`p_U = 1` at :math:`k = N`. Its coverage is at
least :math:`1 - \alpha` for every p and N, which is what a claim "the design meets the
requirement with probability ≥ p_L at 95 % confidence" needs; the price is a somewhat wide
interval. Wilson's score interval (J. Am. Stat. Assoc. 22 (1927) 209–212),

.. math::

    \frac{\hat p + \frac{z^2}{2N} \pm z \sqrt{\frac{\hat p(1-\hat p)}{N} + \frac{z^2}{4N^2}}}
         {1 + z^2/N}, \qquad z = \Phi^{-1}(1 - \alpha/2),

is available as ``method="wilson"``: its coverage is near the nominal level on average but
dips below it at some (p, N). Both come from :meth:`scipy.stats.binomtest`'s ``proportion_ci``
(``exact`` and ``wilson``) and are defined at k = 0 and k = N.

**Percentiles.** Over the cases with a value (NaN excluded, counted in ``n_nan``), as order
statistics: the q-th percentile is the smallest value with at least q % of the cases at or
below it (``numpy.percentile(method="inverted_cdf")``), a value some case had, so an ``inf``
sorts as the worst instead of turning an interpolation into NaN. Its distribution-free interval
is a pair of order statistics (H. A. David and H. N. Nagaraja, *Order Statistics*, 3rd ed.,
2003, §7.1): with :math:`B \sim \mathrm{Bin}(n, q)` the number of cases below the true
percentile, the ranks :math:`j = F_B^{-1}(\alpha/2)` and :math:`k = F_B^{-1}(1-\alpha/2) + 1`
give :math:`P(X_{(j)} \le x_q \le X_{(k)}) \ge 1 - \alpha`; a rank outside 1..n leaves that side
open (±inf).

**Convergence.** Each estimate recomputed on the first N' cases for N' = 10, 20, 50, 100, 200,
500, … and N: the plain Monte Carlo sample of
:meth:`~flexsat.design.parameter_space.ParameterSpace.sample` is prefix-consistent, so the first
N' cases are the run of N' cases.

**Sensitivity.** Two tools, by the design of the sample:

* a Saltelli design (:meth:`~flexsat.design.parameter_space.ParameterSpace.sobol_design`) →
  :func:`sobol_indices`: Sobol' first-order indices :math:`S_i = V[E(Y|X_i)]/V(Y)` and total
  indices :math:`S_{Ti} = E[V(Y|X_{\sim i})]/V(Y)` (Saltelli et al., Comput. Phys. Commun. 181
  (2010) 259–270; SALib.analyze.sobol) with bootstrap confidence intervals; the ranking is by
  total index (a parameter matters if it matters through any interaction). Costs N (d + 2) runs;
* any other sample (plain Monte Carlo, Latin hypercube, a grid) → :func:`sample_sensitivity`:
  Spearman's rank correlation :math:`\rho_s` by default (free, for monotone effects; the
  ranking is by :math:`|\rho_s|`), or SALib's RBD-FAST first-order indices (Tarantola et al.,
  Reliab. Eng. Syst. Saf. 91 (2006) 717–727; Plischke, ibid. 95 (2010) 354–360), which also see
  non-monotone effects, from the same sample (it needs no special design but a few hundred
  cases).

Measured (tests/design/test_monte_carlo_statistics.py): for m = x², x ~ N(1, 0.5²),
P(m ≤ 1.5) = 0.6735, the 95 % intervals from N = 200 cases covered the true value in 0.956
(Clopper–Pearson) and 0.944 (Wilson) of 500 seeded repetitions (0.94 for both in the test's 50);
at a nominal 80 % they cover 0.826 and 0.798. The Ishigami function's Sobol' indices (a = 7,
b = 0.1) from 4,096 base points (20,480 cases) are within 0.002 of the closed form, against
bootstrap half-widths of 0.015–0.05.

Sobol' indices need a value in every case: a metric with NaN is refused; analyse the indicator
of a requirement (``requirement.met(y).astype(float)``) instead, whose Sobol' indices rank the
parameters by their effect on meeting it. The rank tools use the cases with a value.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from scipy import stats

from flexsat.design.parameter_space import (
    SampleTable,
    SobolDesign,
    require_si_unit,
    si_scalar,
)
from flexsat.input_checks import FieldError, require_count
from flexsat.units import FloatArray, QuantityLike

#: the percentiles reported by default
DEFAULT_PERCENTILES = (1.0, 5.0, 50.0, 95.0, 99.0)
#: the interval methods of :func:`proportion_interval` and their names in scipy's binomtest
INTERVAL_METHODS = {"clopper_pearson": "exact", "wilson": "wilson"}
#: the relations a requirement may state
RELATIONS = ("<=", ">=")

IntArray = npt.NDArray[np.int_]


def _confidence(confidence) -> float:
    c = float(confidence) if isinstance(confidence, (int, float)) else math.nan
    if isinstance(confidence, bool) or not 0 < c < 1:
        raise FieldError(
            "confidence", f"must be a number in (0, 1) such as 0.95, got {confidence!r}"
        )
    return c


def _metric(values, field_path: str) -> FloatArray:
    """A 1-D float array of at least one case (NaN and inf allowed: see the module)."""
    if isinstance(values, (str, bytes)):
        raise FieldError(field_path, f"must be an array of numbers, got the string {values!r}")
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise FieldError(
            field_path, f"must be an array of numbers, got {type(values).__name__}"
        ) from None
    if arr.ndim != 1 or arr.size == 0:
        raise FieldError(
            field_path,
            f"must be a 1-D array over the cases with one case or more, got shape {arr.shape}",
        )
    return arr


@dataclass(frozen=True)
class Requirement:
    """``metric relation threshold``: ``relation`` ``"<="`` or ``">="``, ``threshold`` in
    ``unit`` (the metric's SI unit; a unit string such as ``"2 deg"`` is converted)."""

    metric: str
    relation: str
    threshold: float
    unit: str = ""

    if TYPE_CHECKING:  # the constructor takes a quantity; ``threshold`` holds the SI float

        def __init__(
            self, metric: str, relation: str, threshold: QuantityLike, unit: str = ...
        ) -> None: ...

    def __post_init__(self) -> None:
        f = f"requirement {self.metric!r}"
        if not isinstance(self.metric, str) or not self.metric.strip():
            raise FieldError(
                "requirement.metric", f"must be a non-empty metric name, got {self.metric!r}"
            )
        if self.relation not in RELATIONS:
            raise FieldError(
                f"{f}.relation", f"must be one of {', '.join(RELATIONS)}, got {self.relation!r}"
            )
        require_si_unit(self.unit, f)
        object.__setattr__(
            self, "threshold", si_scalar(self.threshold, self.unit, f"{f}.threshold")
        )

    @property
    def label(self) -> str:
        return f"{self.metric} {self.relation} {self.threshold:g} {self.unit}".rstrip()

    def met(self, values: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Per case, whether the requirement is met (False where the metric is NaN)."""
        arr = _metric(values, self.metric)
        with np.errstate(invalid="ignore"):
            return arr <= self.threshold if self.relation == "<=" else arr >= self.threshold


def requirement_from_spec(
    metric: str, spec: Mapping, unit: str, field_path: str | None = None
) -> Requirement:
    """A requirement from its scenario dict: ``{max: "8 s"}`` (metric ≤ 8 s) or ``{min: ...}``
    (metric ≥ ...), in the metric's SI ``unit``; errors name ``field_path``."""
    f = field_path or metric
    if not isinstance(spec, Mapping) or len(spec) != 1 or next(iter(spec)) not in ("max", "min"):
        raise FieldError(
            f, f"give exactly one of max: (metric <= value) or min: (metric >= value), got {spec!r}"
        )
    key, value = next(iter(spec.items()))
    require_si_unit(unit, f)
    return Requirement(
        metric, "<=" if key == "max" else ">=", si_scalar(value, unit, f"{f}.{key}"), unit
    )


@dataclass(frozen=True)
class ProbabilityEstimate:
    """``successes`` of ``n`` cases met ``requirement``: the estimate ``probability`` and its
    interval [``low``, ``high``] at ``confidence`` by ``method``."""

    requirement: Requirement
    successes: int
    n: int
    probability: float
    low: float
    high: float
    confidence: float
    method: str

    def as_dict(self) -> dict[str, Any]:
        """Plain numbers and strings (a summary JSON's entry)."""
        r = self.requirement
        return {
            "requirement": r.label,
            "metric": r.metric,
            "relation": r.relation,
            "threshold": r.threshold,
            "unit": r.unit,
            "successes": self.successes,
            "n": self.n,
            "probability": self.probability,
            "low": self.low,
            "high": self.high,
            "confidence": self.confidence,
            "method": self.method,
        }


def proportion_interval(
    successes: int, n: int, confidence: float = 0.95, method: str = "clopper_pearson"
) -> tuple[float, float]:
    """The interval of a binomial proportion from ``successes`` of ``n`` (see the module)."""
    if method not in INTERVAL_METHODS:
        raise FieldError("method", f"must be one of {', '.join(INTERVAL_METHODS)}, got {method!r}")
    count = require_count(n, "n")
    if (
        isinstance(successes, bool)
        or not float(successes).is_integer()
        or not 0 <= successes <= count
    ):
        raise FieldError("successes", f"must be an integer in 0..n = {count}, got {successes!r}")
    ci = stats.binomtest(int(successes), count).proportion_ci(
        confidence_level=_confidence(confidence), method=INTERVAL_METHODS[method]
    )
    return float(ci.low), float(ci.high)


def probability_of_meeting(
    values: npt.ArrayLike,
    requirement: Requirement,
    confidence: float = 0.95,
    method: str = "clopper_pearson",
) -> ProbabilityEstimate:
    """The probability that a case meets ``requirement``, from the metric over the N cases."""
    if not isinstance(requirement, Requirement):
        raise FieldError("requirement", f"must be a Requirement, got {requirement!r}")
    met = requirement.met(values)
    k, n = int(np.count_nonzero(met)), int(met.size)
    low, high = proportion_interval(k, n, confidence, method)
    return ProbabilityEstimate(requirement, k, n, k / n, low, high, _confidence(confidence), method)


def _percentile_rule(q, field_path: str = "q") -> FloatArray:
    try:
        arr = np.atleast_1d(np.asarray(q, dtype=float))
    except (TypeError, ValueError):
        raise FieldError(
            field_path, f"percentiles must be numbers in [0, 100], got {q!r}"
        ) from None
    if arr.ndim != 1 or arr.size == 0 or not np.all((arr >= 0) & (arr <= 100)):
        raise FieldError(field_path, f"percentiles must be numbers in [0, 100], got {q!r}")
    return arr


def percentile_interval(
    values: npt.ArrayLike, q: float, confidence: float = 0.95, field_path: str = "metric"
) -> tuple[float, float, float]:
    """The q-th percentile of the cases with a value and its order-statistic interval (see the
    module): ``(estimate, low, high)``, NaNs if no case has a value."""
    c = _confidence(confidence)
    qs = _percentile_rule(q)
    if np.ndim(q) != 0:
        raise FieldError("q", f"must be a single percentile in [0, 100], got {q!r}")
    qq = float(qs[0])
    x = np.sort(_metric(values, field_path))
    x = x[~np.isnan(x)]
    n = x.size
    if n == 0:
        return math.nan, math.nan, math.nan
    estimate = float(np.percentile(x, qq, method="inverted_cdf"))
    b = stats.binom(n, qq / 100)
    alpha = 1 - c
    j = int(b.ppf(alpha / 2))
    k = int(b.ppf(1 - alpha / 2)) + 1
    low = float(x[j - 1]) if j >= 1 else -math.inf
    high = float(x[k - 1]) if k <= n else math.inf
    return estimate, low, high


@dataclass(frozen=True)
class MetricSummary:
    """One metric over the cases: ``n`` cases, ``n_nan`` without a value; the rest over the cases
    with one: ``mean``, ``sd`` (sample, ddof 1; NaN for fewer than 2), ``minimum``, ``maximum``,
    ``percentiles`` q → value (see the module)."""

    name: str
    n: int
    n_nan: int
    mean: float
    sd: float
    minimum: float
    maximum: float
    percentiles: dict[float, float]

    def as_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "n": self.n,
            "n_nan": self.n_nan,
            "mean": self.mean,
            "sd": self.sd,
            "min": self.minimum,
            "max": self.maximum,
            "percentiles": {f"{q:g}": v for q, v in self.percentiles.items()},
        }


def metric_summary(
    values: npt.ArrayLike, name: str = "metric", q: Sequence[float] = DEFAULT_PERCENTILES
) -> MetricSummary:
    """Count, NaN count, mean, sd, extremes and percentiles of one metric (NaN-aware)."""
    arr = _metric(values, name)
    qs = _percentile_rule(q)
    x = arr[~np.isnan(arr)]
    if x.size == 0:
        nan = math.nan
        return MetricSummary(
            name, arr.size, arr.size, nan, nan, nan, nan, {float(p): nan for p in qs}
        )
    with np.errstate(invalid="ignore"):  # inf - inf in the sd of a metric holding inf
        sd = float(np.std(x, ddof=1)) if x.size > 1 else math.nan
    pct = np.percentile(x, qs, method="inverted_cdf")
    return MetricSummary(
        name,
        arr.size,
        int(arr.size - x.size),
        float(np.mean(x)),
        sd,
        float(x.min()),
        float(x.max()),
        {float(p): float(v) for p, v in zip(qs, pct)},
    )


def checkpoints(n: int, first: int = 10) -> IntArray:
    """The case counts of a convergence table: ``first`` × 1, 2, 5, 10, 20, 50, … below ``n``,
    and ``n``."""
    total = require_count(n, "n")
    points = []
    decade = require_count(first, "first")
    while decade < total:
        points += [m * decade for m in (1, 2, 5) if m * decade < total]
        decade *= 10
    return np.array(points + [total])


@dataclass(frozen=True)
class Convergence:
    """An estimate (``label``) and its interval on the first ``n[i]`` cases."""

    label: str
    n: IntArray
    estimate: FloatArray
    low: FloatArray
    high: FloatArray
    confidence: float

    def as_dict(self) -> dict[str, Any]:
        return {
            "label": self.label,
            "confidence": self.confidence,
            "n": self.n.tolist(),
            "estimate": self.estimate.tolist(),
            "low": self.low.tolist(),
            "high": self.high.tolist(),
        }


def probability_convergence(
    values: npt.ArrayLike,
    requirement: Requirement,
    confidence: float = 0.95,
    method: str = "clopper_pearson",
    points: Sequence[int] | None = None,
) -> Convergence:
    """The probability of meeting ``requirement`` and its interval on the first N' cases, N' in
    ``points`` (default :func:`checkpoints`)."""
    arr = _metric(values, requirement.metric)
    ns = _points(points, arr.size)
    rows = [probability_of_meeting(arr[:m], requirement, confidence, method) for m in ns]
    return Convergence(
        f"P({requirement.label})",
        ns,
        np.array([r.probability for r in rows]),
        np.array([r.low for r in rows]),
        np.array([r.high for r in rows]),
        _confidence(confidence),
    )


def percentile_convergence(
    values: npt.ArrayLike,
    q: float,
    name: str = "metric",
    confidence: float = 0.95,
    points: Sequence[int] | None = None,
) -> Convergence:
    """The q-th percentile and its order-statistic interval on the first N' cases."""
    arr = _metric(values, name)
    ns = _points(points, arr.size)
    rows = np.array([percentile_interval(arr[:m], q, confidence, name) for m in ns])
    return Convergence(
        f"{name} p{q:g}", ns, rows[:, 0], rows[:, 1], rows[:, 2], _confidence(confidence)
    )


def _points(points: Sequence[int] | None, n: int) -> IntArray:
    if points is None:
        return checkpoints(n)
    ns = np.array([require_count(p, "points") for p in points])
    if ns.size == 0 or np.any(ns > n) or np.any(np.diff(ns) <= 0):
        raise FieldError("points", f"must be increasing case counts in 1..{n}, got {points!r}")
    return ns


# -- sensitivity -----------------------------------------------------------------------------------
@dataclass(frozen=True)
class SobolIndices:
    """Sobol' first-order (``first``) and total (``total``) indices per parameter (``names``
    order) with the half-widths of their bootstrap intervals at ``confidence``."""

    names: list[str]
    first: FloatArray
    first_conf: FloatArray
    total: FloatArray
    total_conf: FloatArray
    confidence: float
    n_base: int

    @property
    def ranking(self) -> list[str]:
        """The parameter names by decreasing total index."""
        return [self.names[i] for i in np.argsort(-self.total, kind="stable")]

    def as_dict(self) -> dict[str, Any]:
        return {
            "method": "sobol",
            "confidence": self.confidence,
            "n_base": self.n_base,
            "ranking": self.ranking,
            "indices": {
                n: {"S1": float(s1), "S1_conf": float(c1), "ST": float(st), "ST_conf": float(ct)}
                for n, s1, c1, st, ct in zip(
                    self.names, self.first, self.first_conf, self.total, self.total_conf
                )
            },
        }


def sobol_indices(
    design: SobolDesign,
    y: npt.ArrayLike,
    name: str = "metric",
    confidence: float = 0.95,
    num_resamples: int = 100,
    seed: int = 0,
) -> SobolIndices:
    """Sobol' indices of the metric ``y`` over the cases of a Saltelli ``design`` (see the
    module); ``y`` must have a value in every case."""
    if not isinstance(design, SobolDesign):
        raise FieldError(
            "design",
            f"must be a SobolDesign (ParameterSpace.sobol_design), got {type(design).__name__}",
        )
    from SALib.analyze import sobol as salib_sobol

    arr = _metric(y, name)
    if arr.size != len(design.table):
        raise FieldError(name, f"has {arr.size} cases, the Sobol' design {len(design.table)}")
    if not np.all(np.isfinite(arr)):
        raise FieldError(
            name,
            "Sobol' indices need a finite value in every case; "
            f"{int(np.sum(~np.isfinite(arr)))} are NaN or inf (analyse a "
            f"requirement's indicator instead)",
        )
    result = salib_sobol.analyze(
        design.problem,
        arr,
        calc_second_order=design.second_order,
        num_resamples=require_count(num_resamples, "num_resamples"),
        conf_level=_confidence(confidence),
        seed=seed,
    )
    return SobolIndices(
        list(design.problem["names"]),
        np.asarray(result["S1"]),
        np.asarray(result["S1_conf"]),
        np.asarray(result["ST"]),
        np.asarray(result["ST_conf"]),
        _confidence(confidence),
        design.n_base,
    )


#: the methods of :func:`sample_sensitivity`
SAMPLE_METHODS = ("spearman", "rbd_fast")
#: the fewest cases with a value a sample ranking takes: Spearman's interval uses n - 3
MIN_RANKING_CASES = 4


@dataclass(frozen=True)
class SensitivityRanking:
    """A ranking from a given sample: ``scores`` per parameter (``names`` order; |ρ_s| for
    ``spearman``, S1 for ``rbd_fast``), ``signed`` (ρ_s itself, or S1), ``conf`` (RBD-FAST's
    bootstrap half-width; for Spearman the half-width of the Fisher-z interval of ρ_s), the
    number of cases ``n`` used."""

    names: list[str]
    scores: FloatArray
    signed: FloatArray
    conf: FloatArray
    method: str
    n: int

    @property
    def ranking(self) -> list[str]:
        return [self.names[i] for i in np.argsort(-self.scores, kind="stable")]

    def as_dict(self) -> dict[str, Any]:
        return {
            "method": self.method,
            "n": self.n,
            "ranking": self.ranking,
            "scores": {
                n: {"score": float(s), "signed": float(g), "conf": float(c)}
                for n, s, g, c in zip(self.names, self.scores, self.signed, self.conf)
            },
        }


def sample_sensitivity(
    table: SampleTable,
    y: npt.ArrayLike,
    name: str = "metric",
    method: str = "spearman",
    confidence: float = 0.95,
    seed: int = 0,
) -> SensitivityRanking:
    """A sensitivity ranking from any sample (see the module), over the cases where ``y`` has a
    value.

    Spearman's interval: :math:`\\tanh(\\operatorname{artanh}\\rho_s \\pm
    z\\sqrt{1.06/(n-3)})` (Fieller, Hartley & Pearson, Biometrika 44 (1957) 470–481), reported
    as the larger half-width.
    """
    if not isinstance(table, SampleTable):
        raise FieldError("table", f"must be a SampleTable, got {type(table).__name__}")
    if method not in SAMPLE_METHODS:
        raise FieldError("method", f"must be one of {', '.join(SAMPLE_METHODS)}, got {method!r}")
    c = _confidence(confidence)
    arr = _metric(y, name)
    if arr.size != len(table):
        raise FieldError(name, f"has {arr.size} cases, the table {len(table)}")
    keep = ~np.isnan(arr)
    x, yy = table.matrix()[keep], arr[keep]
    n = int(keep.sum())
    names = table.names
    if method == "spearman":
        if n < MIN_RANKING_CASES:
            raise FieldError(
                name,
                f"Spearman's ranking needs {MIN_RANKING_CASES} cases with a value or more, got {n}",
            )
        rho = np.array([stats.spearmanr(x[:, j], yy).statistic for j in range(len(names))])
        z = stats.norm.ppf(0.5 + c / 2) * math.sqrt(1.06 / (n - 3))
        with np.errstate(divide="ignore"):
            centre = np.arctanh(np.clip(rho, -1, 1))
        conf = np.maximum(np.tanh(centre + z) - rho, rho - np.tanh(centre - z))
        return SensitivityRanking(names, np.abs(rho), rho, conf, method, n)
    from SALib.analyze import rbd_fast

    problem = {
        "num_vars": len(names),
        "names": names,
        "bounds": [[float(x[:, j].min()), float(x[:, j].max())] for j in range(len(names))],
    }
    result = rbd_fast.analyze(problem, x, yy, conf_level=c, seed=seed)
    s1 = np.asarray(result["S1"])
    return SensitivityRanking(names, s1, s1, np.asarray(result["S1_conf"]), method, n)


def monte_carlo_summary(
    metrics: Mapping[str, FloatArray],
    requirements: Sequence[Requirement],
    confidence: float = 0.95,
    method: str = "clopper_pearson",
    q: Sequence[float] = DEFAULT_PERCENTILES,
) -> dict:
    """The summary of a run as plain numbers (a JSON's content): per requirement its probability
    estimate and convergence, per metric its summary and the convergence of its percentiles."""
    for r in requirements:
        if not isinstance(r, Requirement):
            raise FieldError("requirements", f"must be Requirement objects, got {r!r}")
        if r.metric not in metrics:
            raise ValueError(
                f"requirement {r.metric!r}: no such metric; metrics: {', '.join(metrics)}"
            )
    return {
        "requirements": [
            {
                **probability_of_meeting(metrics[r.metric], r, confidence, method).as_dict(),
                "convergence": probability_convergence(
                    metrics[r.metric], r, confidence, method
                ).as_dict(),
            }
            for r in requirements
        ],
        "metrics": {
            k: {
                **metric_summary(v, k, q).as_dict(),
                "convergence": [percentile_convergence(v, p, k, confidence).as_dict() for p in q],
            }
            for k, v in metrics.items()
        },
    }


__all__ = [
    "DEFAULT_PERCENTILES",
    "INTERVAL_METHODS",
    "MIN_RANKING_CASES",
    "SAMPLE_METHODS",
    "Convergence",
    "MetricSummary",
    "ProbabilityEstimate",
    "Requirement",
    "SensitivityRanking",
    "SobolIndices",
    "checkpoints",
    "metric_summary",
    "monte_carlo_summary",
    "percentile_convergence",
    "percentile_interval",
    "probability_convergence",
    "probability_of_meeting",
    "proportion_interval",
    "requirement_from_spec",
    "sample_sensitivity",
    "sobol_indices",
]
