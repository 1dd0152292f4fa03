r"""Index of catalogue star pairs by inter-star angle: the k-vector of Mortari and a brute-force
scan with the same interface (Junkins, Pollock & Rahman 1990 §2.3.4: measured inter-star angles
are matched against catalogue pairs).

Every pair of catalogue stars closer than ``max_angle`` (a camera's corner-to-corner field) is
stored with its angle :math:`\theta_{ab} = 2 \arcsin(|r_a - r_b|/2)` (the chord form: accurate
to round-off at small angles, where :math:`\arccos(r_a\cdot r_b)` loses half its digits).

**k-vector** (Mortari, "Search-less algorithm for star pattern recognition", J. Astronaut.
Sci. 45(2), 1997, eqs. 1–6): the n angles are sorted, :math:`s_0 \le \dots \le s_{n-1}`, and a
line :math:`z(i) = m i + q` is drawn through :math:`(0, s_0 - \xi)` and
:math:`(n - 1, s_{n-1} + \xi)` with :math:`\xi` a few ulps of the largest angle; the k-vector
holds :math:`k_i = \#\{j : s_j \le z(i)\}`. A range query :math:`[a, b]` is two index
computations, :math:`j_b = \lfloor (a - q)/m \rfloor`, :math:`j_t = \lceil (b - q)/m \rceil`,
and the candidates are :math:`s_{k_{j_b - 1}}, \dots, s_{k_{j_t} - 1}`: a superset (a few
extra entries where the angle distribution departs from the line) trimmed by comparing the
candidates with the bounds. No search, O(1) per query plus the answer.

The brute-force index compares every stored angle with the bounds: O(n) per query, the
reference the k-vector is benchmarked and tested against.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from flexsat import limits
from flexsat.attitude.star_catalog import StarCatalog
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["catalog_pairs", "expected_pairs", "KVectorIndex", "BruteForceIndex", "pair_angles"]

IntArray = npt.NDArray[np.int64]


def pair_angles(a: FloatArray, b: FloatArray) -> FloatArray:
    """Angle between unit vectors (..., 3), 2 arcsin(|a − b|/2), rad."""
    return 2.0 * np.arcsin(np.clip(0.5 * np.linalg.norm(a - b, axis=-1), 0.0, 1.0))


def expected_pairs(n_stars: int, max_angle: float) -> float:
    """Pairs of ``n_stars`` stars uniform on the sphere closer than ``max_angle`` rad:
    C(n, 2) times the fraction of the sphere within the angle of a point, (1 − cos θ)/2. The
    real sky is denser towards the galactic plane, by up to about 2 for naked-eye stars."""
    return 0.5 * n_stars * (n_stars - 1) * 0.5 * (1.0 - np.cos(max_angle))


def catalog_pairs(catalog: StarCatalog, max_angle: float) -> tuple[IntArray, IntArray, FloatArray]:
    """(first, second, angle): rows of every catalogue pair within ``max_angle`` rad.

    Raises
    ------
    ValueError
        For a non-positive ``max_angle``, or when no pair is that close (a catalogue too small
        or too sparse for the field of view).
    """
    if not isinstance(catalog, StarCatalog):
        raise FieldError("catalog", f"must be a StarCatalog, got {type(catalog).__name__}")
    ang = float(max_angle)
    if not 0 < ang < np.pi:
        raise FieldError("max_angle", f"must lie in (0, π) rad, got {max_angle!r}")
    expected = expected_pairs(len(catalog), ang)
    if expected > limits.MAX_CATALOG_PAIRS:
        raise FieldError(
            "catalog",
            f"its {len(catalog):,} stars form about {expected:.3g} pairs within "
            f"{np.degrees(ang):.3g}° (the cameras' field), above the limit "
            f"{limits.MAX_CATALOG_PAIRS:,} (flexsat.limits.MAX_CATALOG_PAIRS); a brighter "
            f"magnitude limit or a narrower field of view",
        )
    tree = cKDTree(catalog.vectors)
    pairs = tree.query_pairs(2.0 * np.sin(0.5 * ang), output_type="ndarray")
    if pairs.shape[0] == 0:
        raise FieldError(
            "catalog",
            f"no two of its {len(catalog)} stars lie within "
            f"{np.degrees(ang):.3g}° of each other; the index needs at least one "
            f"pair in a field of view",
        )
    theta = pair_angles(catalog.vectors[pairs[:, 0]], catalog.vectors[pairs[:, 1]])
    return pairs[:, 0].astype(np.int64), pairs[:, 1].astype(np.int64), theta


class _PairIndex:
    """Shared storage: pairs sorted by angle."""

    def __init__(self, catalog: StarCatalog, max_angle: float) -> None:
        first, second, theta = catalog_pairs(catalog, max_angle)
        order = np.argsort(theta, kind="stable")
        self.catalog = catalog
        self.max_angle = float(max_angle)
        self.first, self.second, self.angles = first[order], second[order], theta[order]

    def __len__(self) -> int:
        return self.angles.size

    def count(self, low: npt.ArrayLike, high: npt.ArrayLike) -> int:
        """How many (query, pair) rows :meth:`query` returns for these bounds, counted on the
        sorted angles without building them (the size a caller checks before asking)."""
        low, high = np.asarray(low, float), np.asarray(high, float)
        stop = np.searchsorted(self.angles, high, side="right")
        start = np.searchsorted(self.angles, low, side="left")
        return int(np.maximum(stop - start, 0).sum())

    def query(self, low: npt.ArrayLike, high: npt.ArrayLike) -> tuple[IntArray, IntArray]:
        """(query, pair): for every query q, the rows ``pair`` of the stored pairs with
        ``low[q] <= angle <= high[q]``, flattened (query index repeated per match)."""
        raise NotImplementedError


class KVectorIndex(_PairIndex):
    """Mortari's k-vector over the catalogue pairs within ``max_angle`` (module docstring)."""

    def __init__(self, catalog: StarCatalog, max_angle: float) -> None:
        super().__init__(catalog, max_angle)
        s, n = self.angles, self.angles.size
        xi = 4 * np.finfo(float).eps * max(abs(s[-1]), 1.0)
        self.q = s[0] - xi
        self.m = (s[-1] - s[0] + 2 * xi) / max(n - 1, 1)
        self.k = np.searchsorted(s, self.m * np.arange(n) + self.q, side="right")

    def query(self, low: npt.ArrayLike, high: npt.ArrayLike) -> tuple[IntArray, IntArray]:
        low, high = np.asarray(low, float), np.asarray(high, float)
        n = self.angles.size
        jb = np.floor((low - self.q) / self.m).astype(np.int64) - 1
        jt = np.ceil((high - self.q) / self.m).astype(np.int64)
        start = np.where(jb < 0, 0, self.k[np.clip(jb, 0, n - 1)])
        stop = self.k[np.clip(jt, 0, n - 1)]
        stop = np.where(jt < 0, 0, np.where(jt >= n, n, stop))
        stop = np.maximum(stop, start)
        counts = stop - start
        qid = np.repeat(np.arange(low.size), counts)
        # the rows start[q], ..., stop[q] - 1 of every query, without a Python loop
        offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
        rows = np.repeat(start, counts) + offsets
        s = self.angles[rows]
        keep = (s >= low[qid]) & (s <= high[qid])  # trim the k-vector's superset
        return qid[keep], rows[keep]


class BruteForceIndex(_PairIndex):
    """Every stored angle compared with every query's bounds (the reference matcher)."""

    def query(self, low: npt.ArrayLike, high: npt.ArrayLike) -> tuple[IntArray, IntArray]:
        low, high = np.asarray(low, float), np.asarray(high, float)
        qids: list[IntArray] = []
        rows: list[IntArray] = []
        for q in range(low.size):
            r = np.flatnonzero((self.angles >= low[q]) & (self.angles <= high[q]))
            qids.append(np.full(r.size, q))
            rows.append(r)
        if not rows:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        return np.concatenate(qids).astype(np.int64), np.concatenate(rows).astype(np.int64)
