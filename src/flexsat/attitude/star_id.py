r"""Lost-in-space star-pattern identification by inter-star angles (Junkins, Pollock & Rahman
1990, §2.3.4; Junkins, White & Turner, J. Astronaut. Sci. 25(3), 1977).

The paper's rule: the measured inter-star angles are compared with catalogue pairs; when at
least three measured inter-star-angle *triplets* (triangles of three measured stars whose three
angles all match one catalogue triangle) match to within 5″ in each of two fields of view, the
stars are identified "with essentially probability 1"; measured and catalogued stars that did
not match are deleted. Here, per field of view (:func:`match_field`):

1. **Pairs.** Every measured pair (i, j) with angle θ_ij is looked up in the pair index
   (:mod:`flexsat.attitude.pair_index`): the catalogue pairs (a, b) with
   |θ_ab − θ_ij| <= tolerance.
2. **Hypotheses.** Each such pair votes for a ∈ {i, j} and b ∈ {i, j}; a measured star's
   hypothesis is its most voted catalogue star, kept when it has at least ``min_votes`` votes
   (it closes a triangle) and no other catalogue star has as many (an ambiguous star is left
   unidentified). A real star collects one vote per other real star in the field; a catalogue
   star picks up a spurious vote with probability ≈ n_cat·sin θ·2·tol/2 per pair (≈ 0.01 for
   5,000 stars, 5″), so the true hypothesis wins by an order of magnitude.
3. **Triplets.** Among the hypotheses, a pair is consistent when the catalogue angle between
   their hypotheses matches the measured angle within the tolerance (and they are distinct
   stars). The star with the most inconsistencies (ties: fewest votes) is deleted until every
   pair left is consistent; the m stars left then form C(m, 3) matched triplets, every
   triangle's three angles within tolerance.

Across fields (:func:`identify_frames`): a field is identified with at least ``min_triplets``
matched triplets (3, i.e. 4 mutually consistent stars), and the identification is accepted when
at least ``min_fields`` (2) fields are. The attitude is then fitted to every matched star of the
accepted fields by the q-method (:mod:`flexsat.attitude.fit`) using the known camera
mountings; a star whose residual exceeds the tolerance is deleted and the fit repeated. Angles
alone cannot tell a pattern from its mirror image, nor check one field against another: a single
rotation fitting all fields within the tolerance does both, and a field left below
``min_triplets`` after the deletions rejects the identification.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from math import comb
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.attitude.fit import q_method
from flexsat.attitude.pair_index import BruteForceIndex, KVectorIndex, pair_angles
from flexsat.input_checks import FieldError
from flexsat.units import FloatArray

__all__ = ["FieldMatch", "Identification", "consistent_stars", "match_field", "identify_frames"]

if TYPE_CHECKING:
    from flexsat.attitude.star_camera import StarCamera, StarFrame

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class FieldMatch:
    """One field of view's matches: ``matches[i]`` is the catalogue row of measured star i,
    −1 when it was deleted (unmatched, ambiguous or inconsistent); ``triplets`` the number of
    matched inter-star-angle triplets."""

    camera: int
    matches: IntArray
    triplets: int

    @property
    def n_matched(self) -> int:
        return int(np.count_nonzero(self.matches >= 0))


@dataclass(frozen=True)
class Identification:
    """Outcome of one lost-in-space identification.

    Attributes
    ----------
    accepted : bool
        The paper's acceptance: >= ``min_triplets`` matched triplets in >= ``min_fields``
        fields, confirmed by one attitude fitting every field.
    reason : str
        Why it was rejected ('' when accepted).
    fields : tuple of FieldMatch
        Per camera, after the attitude residual check.
    attitude : ndarray (3, 3) or None
        C_bn, inertial to body.
    quaternion : ndarray (4,) or None
        Its Euler parameters, scalar first.
    covariance : ndarray (3, 3) or None
        QUEST covariance of the body-axis error angles, rad².
    residuals : ndarray
        Angle between each used measured direction and its fitted catalogue direction, rad.
    """

    accepted: bool
    reason: str
    fields: tuple[FieldMatch, ...]
    attitude: FloatArray | None = None
    quaternion: FloatArray | None = None
    covariance: FloatArray | None = None
    residuals: FloatArray = field(default_factory=lambda: np.zeros(0))

    @property
    def n_stars(self) -> int:
        return sum(f.n_matched for f in self.fields)


def match_field(
    vectors: npt.ArrayLike,
    index: KVectorIndex | BruteForceIndex,
    tolerance: float,
    camera: int = 0,
    min_votes: int = 2,
) -> FieldMatch:
    """Identify the stars of one field of view from their unit directions (module docstring,
    steps 1–3).

    Parameters
    ----------
    vectors : array_like (k, 3)
        Measured unit directions (any common frame: only angles are used).
    index : KVectorIndex or BruteForceIndex
        Catalogue pairs by angle.
    tolerance : float
        Largest |measured − catalogue| inter-star angle of a match, rad.
    """
    v = np.asarray(vectors, float)
    k = v.shape[0]
    matches = np.full(k, -1, np.int64)
    if k < 3:
        return FieldMatch(camera, matches, 0)
    n_cat = len(index.catalog)
    I, J = np.triu_indices(k, 1)
    theta = pair_angles(v[I], v[J])
    n_candidates = index.count(theta - tolerance, theta + tolerance)
    if n_candidates > limits.MAX_PAIR_CANDIDATES:
        raise FieldError(
            "vectors",
            f"the field's {k} stars form {I.size:,} pairs matching {n_candidates:,} "
            f"catalogue pairs within the tolerance, above the limit "
            f"{limits.MAX_PAIR_CANDIDATES:,} (flexsat.limits.MAX_PAIR_CANDIDATES); fewer "
            f"(false) stars per field or a smaller tolerance",
        )
    qid, rows = index.query(theta - tolerance, theta + tolerance)
    if qid.size == 0:
        return FieldMatch(camera, matches, 0)
    best, count, runner_up = _tally(I[qid], J[qid], index.first[rows], index.second[rows], k, n_cat)
    hyp = np.flatnonzero((count >= min_votes) & (runner_up < count))
    if hyp.size < 3:
        return FieldMatch(camera, matches, 0)
    cand = best[hyp]
    meas = np.zeros((k, k))
    meas[I, J] = theta
    meas = meas + meas.T
    rv = index.catalog.vectors[cand]
    cat = pair_angles(rv[:, None, :], rv[None, :, :])
    bad = (np.abs(meas[np.ix_(hyp, hyp)] - cat) > tolerance) | (cand[:, None] == cand[None, :])
    np.fill_diagonal(bad, False)
    alive = consistent_stars(bad, count[hyp])
    m = int(alive.sum())
    if m < 3:
        return FieldMatch(camera, matches, 0)
    matches[hyp[alive]] = cand[alive]
    return FieldMatch(camera, matches, comb(m, 3))


#: measured × catalogue stars up to which the votes are tallied in a dense table (64 MB): one
#: bincount, several times faster than sorting the distinct votes, which beyond it cost less
#: memory (300 stars against Hipparcos' 118,218 would be a 280 MB table)
DENSE_TALLY = 2**23


def _tally(
    i: IntArray, j: IntArray, a: IntArray, b: IntArray, k: int, n_cat: int
) -> tuple[IntArray, IntArray, IntArray]:
    """Votes of the matched pairs (measured i, j; catalogue a, b): each votes for a and b as
    the identity of i and of j. Per measured star 0 .. k − 1: its most voted catalogue star
    (the lowest row among equals), that star's votes and the runner-up's (0 when none)."""
    keys = np.concatenate([i * n_cat + a, i * n_cat + b, j * n_cat + a, j * n_cat + b])
    if k * n_cat <= DENSE_TALLY:
        table = np.bincount(keys, minlength=k * n_cat).reshape(k, n_cat)
        best = np.argmax(table, axis=1)
        count = table[np.arange(k), best]
        table[np.arange(k), best] = 0
        return best, count, table.max(axis=1)
    distinct, votes = np.unique(keys, return_counts=True)
    star, cat = np.divmod(distinct, n_cat)
    order = np.lexsort((cat, -votes, star))  # by star, most votes first, lowest row
    star_o, cat_o, votes_o = star[order], cat[order], votes[order]
    first = np.flatnonzero(np.r_[True, star_o[1:] != star_o[:-1]])
    best = np.zeros(k, np.int64)
    count = np.zeros(k, np.int64)
    runner_up = np.zeros(k, np.int64)
    best[star_o[first]] = cat_o[first]
    count[star_o[first]] = votes_o[first]
    has_second = np.r_[first[1:], star_o.size] - first > 1
    runner_up[star_o[first[has_second]]] = votes_o[first[has_second] + 1]
    return best, count, runner_up


def consistent_stars(conflict: npt.NDArray[np.bool_], support: IntArray) -> npt.NDArray[np.bool_]:
    """The stars kept by step 3 (module docstring): while any conflict is left among the
    stars alive, delete the one with the most (ties: the fewest votes, then the first).

    Parameters
    ----------
    conflict : (h, h) bool, symmetric, False on the diagonal
        Whether two hypotheses disagree (their catalogue angle is off the measured one, or
        they name the same catalogue star).
    support : (h,) int
        Each hypothesis' votes.

    Returns
    -------
    (h,) bool
        Alive after the deletions. Each star's count of conflicts with the living is updated
        as stars go (O(h) per deletion, O(h²) in all, where recounting the table each time
        is O(h³): 2 s for 300 hypotheses).
    """
    alive = np.ones(support.size, bool)
    conflicts = conflict.sum(1)
    while True:
        counted = np.where(alive, conflicts, -1)
        worst = counted.max(initial=-1)
        if worst <= 0:
            return alive
        tied = np.flatnonzero(counted == worst)
        gone = tied[np.argmin(support[tied])]
        alive[gone] = False
        conflicts -= conflict[:, gone]


def _triplets(matches: IntArray) -> int:
    m = int(np.count_nonzero(matches >= 0))
    return comb(m, 3) if m >= 3 else 0


def identify_frames(
    frames: Sequence[StarFrame],
    cameras: Sequence[StarCamera],
    index: KVectorIndex | BruteForceIndex,
    tolerance: float,
    min_triplets: int = 3,
    min_fields: int = 2,
    max_refits: int = 3,
) -> Identification:
    """Lost-in-space identification of one set of simultaneous frames (module docstring).

    Parameters
    ----------
    frames : sequence of StarFrame
        One per camera, ``frames[c].camera`` indexing ``cameras``.
    cameras : sequence of StarCamera
        Their mountings (body to camera) and direction noise (the q-method weights).
    index, tolerance
        As :func:`match_field`.
    min_triplets : int
        Matched inter-star-angle triplets a field needs (3 in the paper).
    min_fields : int
        Identified fields needed (2 in the paper).
    """
    fields = [match_field(f.vectors, index, tolerance, f.camera) for f in frames]
    good = [fm.triplets >= min_triplets for fm in fields]
    if sum(good) < min_fields:
        return Identification(
            False,
            f"{sum(good)} of {len(fields)} fields of view have >= "
            f"{min_triplets} matched triplets; {min_fields} needed",
            tuple(fields),
        )
    matches = [
        fm.matches.copy() if ok else np.full(fm.matches.size, -1) for fm, ok in zip(fields, good)
    ]
    for _ in range(max_refits + 1):
        bodies: list[FloatArray] = []
        refs: list[FloatArray] = []
        sigs: list[FloatArray] = []
        where: list[npt.NDArray[np.intp]] = []
        for f, mt in zip(frames, matches):
            cam = cameras[f.camera]
            used = np.flatnonzero(mt >= 0)
            bodies.append(f.vectors[used] @ cam.mounting_matrix)  # v_b = C_cbᵀ v_c
            refs.append(index.catalog.vectors[mt[used]])
            # a noise-free camera is weighted as a thousandth of a pixel (covariance a bound)
            sigs.append(np.full(used.size, max(cam.direction_sigma, 1e-3 * cam.pixel_angle)))
            where.append(used)
        body, ref, sig = np.vstack(bodies), np.vstack(refs), np.concatenate(sigs)
        if body.shape[0] < 3:
            return Identification(
                False,
                "fewer than 3 stars left for the attitude fit",
                tuple(_final(fields, matches)),
            )
        C, beta, P = q_method(body, ref, sig)
        resid = pair_angles(body, ref @ C.T)
        if np.all(resid <= tolerance):
            break
        start = 0
        for c, used in enumerate(where):
            out = resid[start : start + used.size] > tolerance
            matches[c][used[out]] = -1
            start += used.size
    else:
        return Identification(
            False,
            "the attitude fit kept deleting stars whose residual exceeds the tolerance",
            tuple(_final(fields, matches)),
        )
    final = _final(fields, matches)
    n_ok = sum(fm.triplets >= min_triplets for fm in final)
    if n_ok < min_fields:
        return Identification(
            False,
            f"after deleting stars off the fitted attitude, {n_ok} "
            f"fields keep >= {min_triplets} triplets; {min_fields} needed",
            tuple(final),
        )
    return Identification(True, "", tuple(final), C, beta, P, resid)


def _final(fields: Sequence[FieldMatch], matches: Sequence[IntArray]) -> list[FieldMatch]:
    return [FieldMatch(fm.camera, mt, _triplets(mt)) for fm, mt in zip(fields, matches)]
