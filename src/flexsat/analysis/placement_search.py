r"""Candidate-set search: pick ``size`` of the ``candidates`` maximising a score.

:func:`exhaustive`, :func:`greedy` and :func:`exchange` share one interface
``(candidates, size, score)``, where ``score(selection)`` is called on a tuple of candidates in
their given order (larger is better; e.g. :func:`flexsat.analysis.placement.kim_junkins_score`).
The exhaustive search refuses problems of more than ``max_sets`` sets (default 10⁶) before it
enumerates anything: C(36, 12) = 1 251 677 700 is refused at once. Greedy forward selection
is optimal for an additive score and within 1 − 1/e of the optimum for a monotone submodular
one (G. L. Nemhauser, L. A. Wolsey and M. L. Fisher, "An analysis of approximations for
maximizing submodular set functions — I", Mathematical Programming 14, 1978, 265–294); the
exchange search swaps one chosen for one unchosen candidate while that improves the score
(V. V. Fedorov, *Theory of Optimal Experiments*, Academic Press, 1972).
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Callable, Hashable, Sequence
from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from flexsat.input_checks import FieldError, require_count, require_finite

__all__ = [
    "MAX_EXHAUSTIVE_SETS",
    "Score",
    "SearchResult",
    "Selection",
    "exchange",
    "exhaustive",
    "greedy",
]

#: Default limit of :func:`exhaustive`: it refuses to enumerate more candidate sets than this.
MAX_EXHAUSTIVE_SETS = 1_000_000

#: a set of candidates (their labels), in the order of ``candidates``
Selection: TypeAlias = tuple[Hashable, ...]
#: the score of a candidate set, larger is better
Score: TypeAlias = Callable[[Selection], float]


@dataclass(frozen=True)
class SearchResult:
    """Outcome of a candidate-set search.

    Attributes
    ----------
    selection : tuple
        The chosen candidates, in the order of ``candidates``.
    score : float
        ``score(selection)``.
    method : str
        "exhaustive", "greedy" or "exchange".
    evaluations : int
        Distinct sets scored.
    best : tuple of (score, selection)
        Exhaustive: the ``keep`` best sets, best first; otherwise the path taken (one entry per
        greedy step or accepted exchange).
    """

    selection: Selection
    score: float
    method: str
    evaluations: int
    best: tuple[tuple[float, Selection], ...] = ()


def _search_inputs(candidates: Sequence[Hashable], size: int) -> tuple[list[Hashable], int]:
    try:
        cands = list(candidates)
    except TypeError:
        raise FieldError("candidates", f"must be a sequence, got {candidates!r}") from None
    if not cands:
        raise FieldError("candidates", "must not be empty")
    try:
        if len(set(cands)) != len(cands):
            raise FieldError("candidates", "must be distinct")
    except TypeError:
        raise FieldError("candidates", "must be hashable (labels)") from None
    k = require_count(size, "size")
    if k > len(cands):
        raise FieldError("size", f"must be <= the number of candidates ({len(cands)}), got {k}")
    return cands, k


class _Scorer:
    """Calls score on index sets (sorted), caches, counts and checks the values."""

    def __init__(self, cands: list[Hashable], score: Score):
        if not callable(score):
            raise FieldError("score", f"must be callable, got {score!r}")
        self.cands, self.score = cands, score
        self.cache: dict[tuple[int, ...], float] = {}

    def __call__(self, idx: Sequence[int]) -> float:
        key = tuple(sorted(idx))
        if key not in self.cache:
            value = self.score(tuple(self.cands[i] for i in key))
            try:
                value = float(value)
            except (TypeError, ValueError):
                raise FieldError("score", f"must return a number, got {value!r}") from None
            if np.isnan(value):
                raise FieldError("score", f"returned NaN for {tuple(self.cands[i] for i in key)}")
            self.cache[key] = value
        return self.cache[key]

    def labels(self, idx: Sequence[int]) -> Selection:
        return tuple(self.cands[i] for i in sorted(idx))


def exhaustive(
    candidates: Sequence[Hashable],
    size: int,
    score: Score,
    max_sets: int = MAX_EXHAUSTIVE_SETS,
    keep: int = 10,
) -> SearchResult:
    """Score every ``size``-subset of ``candidates``; return the best.

    Refuses (ValueError, before enumerating anything) when C(len(candidates), size) exceeds
    ``max_sets`` (default :data:`MAX_EXHAUSTIVE_SETS` = 10⁶), e.g. C(36, 12) = 1 251 677 700:
    use :func:`greedy` or :func:`exchange` there. Ties keep the first set in lexicographic
    order of candidate positions.
    """
    cands, k = _search_inputs(candidates, size)
    limit = require_count(max_sets, "max_sets")
    count = math.comb(len(cands), k)
    if count > limit:
        raise FieldError(
            "exhaustive",
            f"C({len(cands)}, {k}) = {count:,} candidate sets exceeds max_sets = "
            f"{limit:,}; refusing to enumerate. Use greedy() or exchange() for large problems",
        )
    f = _Scorer(cands, score)
    keep = require_count(keep, "keep")
    heap: list[tuple[float, int, tuple[int, ...]]] = []  # min-heap of (score, -order, idx)
    for order, idx in enumerate(itertools.combinations(range(len(cands)), k)):
        item = (f(idx), -order, idx)
        if len(heap) < keep:
            heapq.heappush(heap, item)
        elif item > heap[0]:
            heapq.heapreplace(heap, item)
    ranked = sorted(heap, reverse=True)
    best = tuple((s, f.labels(idx)) for s, _, idx in ranked)
    return SearchResult(
        selection=best[0][1],
        score=best[0][0],
        method="exhaustive",
        evaluations=len(f.cache),
        best=best,
    )


def greedy(
    candidates: Sequence[Hashable],
    size: int,
    score: Score,
    start: Sequence[Hashable] = (),
) -> SearchResult:
    """Forward selection: add, one at a time, the candidate that maximises the score of the
    enlarged set (``score`` is called on sets of 1 … ``size`` candidates). ``start``: candidates
    already chosen. n·size evaluations at most; optimal when the score is additive
    (modular), within 1 − 1/e of optimal when it is monotone submodular."""
    cands, k = _search_inputs(candidates, size)
    f = _Scorer(cands, score)
    chosen = _positions(cands, start, "start")
    if len(chosen) > k:
        raise FieldError("start", f"has {len(chosen)} candidates, more than size = {k}")
    chosen, path = _greedy(f, len(cands), k, chosen)
    return SearchResult(
        selection=f.labels(chosen),
        score=f(chosen),
        method="greedy",
        evaluations=len(f.cache),
        best=tuple(path),
    )


def _greedy(
    f: _Scorer, n: int, k: int, chosen: list[int]
) -> tuple[list[int], list[tuple[float, Selection]]]:
    chosen, path = list(chosen), []
    while len(chosen) < k:
        best_s, best_i = -np.inf, None
        for i in range(n):
            if i in chosen:
                continue
            s = f(chosen + [i])
            if s > best_s:
                best_s, best_i = s, i
        if best_i is None:  # every score was -inf
            best_i = next(i for i in range(n) if i not in chosen)
        chosen.append(best_i)
        path.append((best_s, f.labels(chosen)))
    return chosen, path


def _positions(cands: list[Hashable], items: Sequence[Hashable], field_name: str) -> list[int]:
    index = {c: i for i, c in enumerate(cands)}
    out = []
    for c in items:
        if c not in index:
            raise FieldError(field_name, f"{c!r} is not a candidate")
        if index[c] in out:
            raise FieldError(field_name, f"{c!r} repeated")
        out.append(index[c])
    return out


def exchange(
    candidates: Sequence[Hashable],
    size: int,
    score: Score,
    start: Sequence[Hashable] | None = None,
    max_rounds: int = 100,
    tol: float = 0.0,
) -> SearchResult:
    """Swap improvement (steepest ascent) from ``start`` (default: the :func:`greedy` set).

    Each round scores every swap of one chosen candidate for one unchosen one (k·(n − k)
    sets) and applies the best if it improves the score by more than ``tol``; stops at a
    1-swap local optimum or after ``max_rounds`` rounds. Never worse than its start.
    """
    cands, k = _search_inputs(candidates, size)
    f = _Scorer(cands, score)
    if start is None:
        chosen, _ = _greedy(f, len(cands), k, [])
    else:
        chosen = _positions(cands, start, "start")
        if len(chosen) != k:
            raise FieldError("start", f"must have size = {k} candidates, got {len(chosen)}")
    rounds = require_count(max_rounds, "max_rounds")
    tol = float(require_finite(tol, "tol"))
    current = f(chosen)
    path = [(current, f.labels(chosen))]
    for _ in range(rounds):
        best_s, best_set = current, None
        for pos in range(k):
            for i in range(len(cands)):
                if i in chosen:
                    continue
                trial = chosen[:pos] + [i] + chosen[pos + 1 :]
                s = f(trial)
                if s > best_s:
                    best_s, best_set = s, trial
        if best_set is None or best_s <= current + tol:
            break
        chosen, current = best_set, best_s
        path.append((current, f.labels(chosen)))
    return SearchResult(
        selection=f.labels(chosen),
        score=current,
        method="exchange",
        evaluations=len(f.cache),
        best=tuple(path),
    )
