"""The published-number check: one value printed in a source, recomputed live, and a tolerance.

A :class:`Check` names the case, the quantity, the source (short citation and equation, table
or section, or a published reference), the value as printed (``published``, in ``unit``) and a
``compute`` callable that recomputes it from the code base each time it is run. Nothing computed
is stored: :func:`evaluate` calls ``compute`` and compares.

Pass rule (as :func:`numpy.isclose`): ``|computed − published| ≤ atol + rtol·|published|``, with
a missing tolerance counted as 0. Every check states why its tolerance is what it is, in a
comment next to it. The rules used across the registry:

- a value the model is meant to reproduce exactly (a formula, a conversion, a solved target):
  **half a unit in the last printed digit** (``atol``) — the printed precision, nothing more;
- a value a discretised model approximates: the acceptance criterion of the issue that asked
  for it (e.g. 0.01 % for 20 beam elements, 1 % for NAFEMS FV2);
- a value of a reconstructed or unpublished model, or a reading of an experiment: the band the
  issue set for it, named in the comment (e.g. ±25 % for the EPS modes).

A published number the code is known not to reproduce, because the paper is wrong (an erratum:
the printed value contradicts the paper's own inputs) or because the model deviates from it for
a documented, argued reason, carries a :class:`Discrepancy`: the value the code is expected to
compute instead and a standalone explanation. Its row is then ``discrepancy``, not ``fail`` —
as long as the computed value matches the explained one within the check's tolerance, so that a
regression is still a failure. Statuses: ``pass``, ``discrepancy``, ``fail``, ``error``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import TYPE_CHECKING, Any

from flexsat.input_checks import FieldError
from flexsat.references import cite, references

if TYPE_CHECKING:
    import numpy as np

#: the columns of the validation table, in order (also the keys of :meth:`CheckResult.as_dict`)
COLUMNS = (
    "case",
    "quantity",
    "source",
    "published",
    "computed",
    "unit",
    "relative_error",
    "tolerance",
    "status",
    "explanation",
)

#: the statuses of :attr:`CheckResult.status`; the last two fail ``flexsat validate``
STATUSES = ("pass", "discrepancy", "fail", "error")


@dataclass(frozen=True)
class Discrepancy:
    """Why a published number is not reproduced, and what is computed instead.

    Parameters
    ----------
    value : float
        The value the code is expected to compute, in the check's unit: the corrected value of
        an erratum (derived from the paper's own inputs) or the documented value of a model
        deviation. The check's tolerance applies to it as to the published value.
    explanation : str
        Standalone: it names the paper (the source column cites it) and states the argument,
        never only a path into the developers' notes, which do not ship.
    """

    value: float
    explanation: str

    def __post_init__(self) -> None:
        if not math.isfinite(self.value):
            raise FieldError("discrepancy.value", f"must be finite, got {self.value!r}")
        if not isinstance(self.explanation, str) or not self.explanation.strip():
            raise FieldError("discrepancy.explanation", "must be a non-empty string")


@dataclass(frozen=True)
class Check:
    """One published number and how to recompute it.

    Parameters
    ----------
    case : str
        Case name (``flexsat validate --case NAME`` selects by it).
    quantity : str
        What is compared, short (e.g. ``"ω_4, open loop"``).
    source : str
        Short citation and equation/table/section, or the published reference.
    published : float
        The value as printed, in ``unit``.
    unit : str
        Display unit of ``published`` and of what ``compute`` returns (``""`` for a pure number).
    compute : callable
        No arguments; recomputes the value live and returns it in ``unit``.
    rtol, atol : float, optional
        Relative and absolute (in ``unit``) tolerance; at least one must be given. ``atol=0``
        alone means exact (counts).
    note : str
        Optional remark shown with the result (an assumption, a fitted value).
    discrepancy : Discrepancy, optional
        Set when the published value is an established erratum or the model deviates from it
        for a documented reason: outside the tolerance but at ``discrepancy.value``, the result
        is ``discrepancy`` rather than ``fail``.
    """

    case: str
    quantity: str
    source: str
    published: float
    unit: str
    compute: Callable[[], float]
    rtol: float | None = None
    atol: float | None = None
    note: str = ""
    discrepancy: Discrepancy | None = None

    def __post_init__(self) -> None:
        for name in ("case", "quantity", "source"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name).strip():
                raise FieldError(name, f"must be a non-empty string, got {getattr(self, name)!r}")
        if self.rtol is None and self.atol is None:
            raise ValueError(f"{self.case} / {self.quantity}: give rtol or atol (or both)")
        for name in ("rtol", "atol"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value >= 0):
                raise FieldError(name, f"must be a finite number >= 0, got {value!r}")
        if not math.isfinite(self.published):
            raise FieldError("published", f"must be finite, got {self.published!r}")
        if not callable(self.compute):
            raise FieldError("compute", "must be callable with no arguments")
        if self.discrepancy is not None and self.passes(self.discrepancy.value):
            raise ValueError(
                f"{self.case} / {self.quantity}: discrepancy.value "
                f"{self.discrepancy.value!r} is within the tolerance of the "
                f"published {self.published!r}: not a discrepancy"
            )

    @property
    def tolerance(self) -> str:
        """The tolerance as text: ``"±0.01 %"``, ``"±5e-05 s"``, ``"exact"``, or both joined."""
        parts = []
        if self.atol is not None and (self.atol > 0 or self.rtol is None):
            parts.append(f"±{self.atol:.3g} {self.unit}".rstrip() if self.atol > 0 else "exact")
        if self.rtol is not None:
            parts.append(f"±{100 * self.rtol:.3g} %")
        return " + ".join(parts)

    def passes(self, computed: float) -> bool:
        return self._within(computed, self.published)

    def matches_discrepancy(self, computed: float) -> bool:
        """Whether ``computed`` is the value the documented discrepancy explains."""
        return self.discrepancy is not None and self._within(computed, self.discrepancy.value)

    def _within(self, computed: float, target: float) -> bool:
        bound = (self.atol or 0.0) + (self.rtol or 0.0) * abs(target)
        return math.isfinite(computed) and abs(computed - target) <= bound


@dataclass(frozen=True)
class CheckResult:
    """The outcome of one :class:`Check`: ``computed`` is None when ``compute`` raised (the
    message is in ``error``). ``passed``: the computed value agrees with the published one."""

    check: Check
    computed: float | None
    passed: bool
    error: str | None = None
    seconds: float = 0.0

    @property
    def relative_error(self) -> float | None:
        """(computed − published) / |published|; None without a value or for published 0."""
        if self.computed is None or self.check.published == 0 or not math.isfinite(self.computed):
            return None
        return (self.computed - self.check.published) / abs(self.check.published)

    @property
    def status(self) -> str:
        """``pass``, ``discrepancy`` (outside the tolerance, at the value a documented erratum or
        deviation explains), ``fail`` (outside the tolerance, unexplained) or ``error``."""
        if self.passed:
            return "pass"
        if self.error:
            return "error"
        if self.computed is not None and self.check.matches_discrepancy(self.computed):
            return "discrepancy"
        return "fail"

    @property
    def failed(self) -> bool:
        """Whether this result fails ``flexsat validate`` (a discrepancy fails it only with
        ``--strict``)."""
        return self.status in ("fail", "error")

    @property
    def stale(self) -> bool:
        """A documented discrepancy that no longer shows: the published value is now
        reproduced, and the explanation should go."""
        return self.passed and self.check.discrepancy is not None

    @property
    def explanation(self) -> str | None:
        """Why the row is not a plain pass, standalone; None for a plain pass."""
        c, d = self.check, self.check.discrepancy
        status = self.status
        if status == "error":
            return f"the computation raised: {self.error}" if self.computed is None else self.error
        if status == "discrepancy":
            assert d is not None  # the status of a check with a discrepancy only
            return d.explanation
        if status == "fail":
            text = (
                f"computed {self.computed:.7g} is outside the tolerance ({c.tolerance}) of "
                f"the published {c.published:.10g}"
            )
            if d is not None:
                text += (
                    f" and of the {d.value:.7g} that the documented discrepancy explains "
                    f"({d.explanation})"
                )
            else:
                text += "; no erratum or model deviation explains it"
            return text + (f"; note: {c.note}" if c.note else "")
        if self.stale:
            assert d is not None  # stale: a discrepancy that no longer shows
            return (
                f"stale discrepancy note: the published value is now reproduced, but the "
                f"check still explains a discrepancy ({d.explanation})"
            )
        return None

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready: the table columns (the source cited by authors and year), then
        ``references`` (full citations), passed, rtol, atol, error, note, discrepancy_value,
        stale, seconds."""
        c = self.check
        computed = self.computed if self.computed is None or math.isfinite(self.computed) else None
        return {
            "case": c.case,
            "quantity": c.quantity,
            "source": cite(c.source),
            "published": c.published,
            "computed": computed,
            "unit": c.unit,
            "relative_error": self.relative_error,
            "tolerance": c.tolerance,
            "status": self.status,
            "explanation": self.explanation,
            "references": references([c.source]),
            "passed": self.passed,
            "rtol": c.rtol,
            "atol": c.atol,
            "error": self.error,
            "note": c.note or None,
            "discrepancy_value": c.discrepancy.value if c.discrepancy else None,
            "stale": self.stale,
            "seconds": round(self.seconds, 4),
        }


def evaluate(check: Check) -> CheckResult:
    """Run one check. Any exception raised while computing (or a value that is not a finite
    real number) makes it fail with the message; it never propagates."""
    start = time.perf_counter()
    try:
        value = check.compute()
        try:
            computed = float(value)
        except (TypeError, ValueError):
            raise TypeError(f"compute returned {value!r}, not a number") from None
    except Exception as exc:  # noqa: BLE001 -- reported in the table, never crashes it
        return CheckResult(
            check, None, False, f"{type(exc).__name__}: {exc}", time.perf_counter() - start
        )
    elapsed = time.perf_counter() - start
    if not math.isfinite(computed):
        return CheckResult(
            check, computed, False, f"computed value is not finite: {computed!r}", elapsed
        )
    return CheckResult(check, computed, check.passes(computed), None, elapsed)


def series(
    case: str,
    quantities: Iterable[str],
    source: str,
    published: Iterable[float],
    unit: str,
    values: Callable[[], Sequence[float] | np.ndarray],
    *,
    rtol: float | None = None,
    atol: float | None = None,
    notes: Iterable[str] | None = None,
    discrepancies: Iterable[Discrepancy | None] | None = None,
) -> list[Check]:
    """One check per entry of a table column: ``values()`` returns the whole computed column
    (cache it with :func:`functools.lru_cache` when it is expensive) and check ``i`` compares
    ``values()[i]`` with ``published[i]``; ``notes`` and ``discrepancies`` (a
    :class:`Discrepancy` or None per entry) are optional, per entry."""
    values_published = list(published)
    names = list(quantities)
    remarks = list(notes) if notes is not None else [""] * len(values_published)
    explained = list(discrepancies) if discrepancies is not None else [None] * len(values_published)
    if not len(names) == len(values_published) == len(remarks) == len(explained):
        raise FieldError(
            "series", "quantities, published, notes and discrepancies must have the same length"
        )
    return [
        Check(case, q, source, float(p), unit, partial(_entry, values, i), rtol, atol, note, d)
        for i, (q, p, note, d) in enumerate(zip(names, values_published, remarks, explained))
    ]


def _entry(values: Callable[[], Sequence[float] | np.ndarray], i: int) -> float:
    """Entry ``i`` of the column ``values()`` (what :func:`evaluate` makes a float)."""
    return values()[i]


__all__ = ["COLUMNS", "STATUSES", "Check", "CheckResult", "Discrepancy", "evaluate", "series"]
