r"""Lost-in-space star-pattern identification by inter-star angles (Junkins, Pollock & Rahman
1990, §2.3.4, L278–L282; Junkins, White & Turner, J. Astronaut. Sci. 25(3), 1977).

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

from flexsat.attitude.fit import q_method
from flexsat.attitude.pair_index import BruteForceIndex, KVectorIndex, pair_angles
from flexsat.units import FloatArray

__all__ = ["FieldMatch", "Identification", "match_field", "identify_frames"]

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
    qid, rows = index.query(theta - tolerance, theta + tolerance)
    if qid.size == 0:
        return FieldMatch(camera, matches, 0)
    a, b = index.first[rows], index.second[rows]
    i, j = I[qid], J[qid]
    votes = np.bincount(
        np.concatenate([i * n_cat + a, i * n_cat + b, j * n_cat + a, j * n_cat + b]),
        minlength=k * n_cat,
    ).reshape(k, n_cat)
    best = np.argmax(votes, axis=1)
    count = votes[np.arange(k), best]
    votes[np.arange(k), best] = 0
    runner_up = votes.max(axis=1)
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
    alive = np.ones(hyp.size, bool)
    support = count[hyp]
    while True:
        conflicts = np.where(alive, (bad & alive[None, :]).sum(1), -1)
        worst = conflicts.max()
        if worst <= 0:
            break
        tied = np.flatnonzero(conflicts == worst)
        alive[tied[np.argmin(support[tied])]] = False
    m = int(alive.sum())
    if m < 3:
        return FieldMatch(camera, matches, 0)
    matches[hyp[alive]] = cand[alive]
    return FieldMatch(camera, matches, comb(m, 3))


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
