r"""A star tracker: two or more star cameras fixed to the body, a catalogue and its pair index,
and the lost-in-space identification (Junkins, Pollock & Rahman 1990, §2.3.4: "two or
more star cameras are fixed to the main body of a spacecraft").

:class:`StarTracker` simulates the frames at a true attitude (:meth:`StarTracker.observe`),
identifies them (:meth:`StarTracker.identify`) and scores the result against the truth
(:func:`score`); :func:`monte_carlo` runs many seeded random attitudes (uniform on SO(3): unit
quaternions from normalised 4-D Gaussians, Shoemake 1992) and returns the statistics the
acceptance tests, the scenario and the validation rows read.

The tolerance must cover the noise of a measured inter-star angle: two stars each with σ per
axis give an angle error of σ√2 (1σ), so the tolerance is required to be at least 3√2 σ of
every camera (a true pair then fails with probability < 0.3 %, and a field has many pairs).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.attitude.fit import rotation_error
from flexsat.attitude.pair_index import BruteForceIndex, KVectorIndex, pair_angles
from flexsat.attitude.star_camera import StarCamera, StarFrame
from flexsat.attitude.star_catalog import StarCatalog
from flexsat.attitude.star_id import Identification, identify_frames
from flexsat.dynamics.attitude import quaternion_to_dcm
from flexsat.input_checks import FieldError, require_count
from flexsat.units import FloatArray, QuantityLike, to_si_array

__all__ = [
    "StarTracker",
    "MonteCarloResult",
    "monte_carlo",
    "check_field_load",
    "check_identifiable",
    "random_attitudes",
    "score",
    "ARCSEC",
    "PAPER_TOLERANCE",
]

#: one arcsecond, rad
ARCSEC = np.pi / 648000.0
#: the paper's matching tolerance, 5″ (Junkins, Pollock & Rahman 1990 §2.3.4)
PAPER_TOLERANCE = 5.0 * ARCSEC
_INDEXES: dict[str, type[KVectorIndex] | type[BruteForceIndex]] = {
    "kvector": KVectorIndex,
    "brute": BruteForceIndex,
}


def random_attitudes(n: int, seed: int | np.random.Generator = 0) -> FloatArray:
    """n attitudes C_bn (n, 3, 3) uniform on SO(3) (module docstring)."""
    q = np.random.default_rng(seed).normal(size=(require_count(n, "n"), 4))
    return quaternion_to_dcm(q / np.linalg.norm(q, axis=1, keepdims=True))


class StarTracker:
    """Star cameras on one body with a catalogue and its pair index.

    Parameters
    ----------
    cameras : sequence of StarCamera
        At least ``min_fields`` cameras (their mountings should point them apart).
    catalog : StarCatalog
        The on-board catalogue; stars fainter than the faintest camera limit are dropped.
    tolerance : float, str or Quantity
        Inter-star angle match tolerance (default the paper's 5″), at least 3√2 σ of every
        camera (module docstring).
    min_triplets, min_fields : int
        The paper's acceptance: 3 matched triplets in each of 2 fields.
    index : {"kvector", "brute"}
        Pair index (the k-vector, or the brute-force scan it is benchmarked against).
    """

    def __init__(
        self,
        cameras: StarCamera | Sequence[StarCamera],
        catalog: StarCatalog,
        tolerance: QuantityLike = PAPER_TOLERANCE,
        min_triplets: int = 3,
        min_fields: int = 2,
        index: str = "kvector",
    ) -> None:
        cams = [cameras] if isinstance(cameras, StarCamera) else list(cameras)
        for c, cam in enumerate(cams):
            if not isinstance(cam, StarCamera):
                raise FieldError(f"cameras[{c}]", f"must be a StarCamera, got {type(cam).__name__}")
        self.min_fields = require_count(min_fields, "min_fields")
        self.min_triplets = require_count(min_triplets, "min_triplets")
        if len(cams) < self.min_fields:
            raise FieldError(
                "cameras",
                f"the identification needs {self.min_fields} fields of view "
                f"(min_fields), got {len(cams)} cameras",
            )
        if not isinstance(catalog, StarCatalog):
            raise FieldError("catalog", f"must be a StarCatalog, got {type(catalog).__name__}")
        tol = to_si_array(tolerance, "rad", "tolerance")
        if tol.ndim != 0 or not np.isfinite(tol) or tol <= 0:
            raise FieldError("tolerance", f"must be one finite angle > 0, got {tolerance!r}")
        self.tolerance = float(tol)
        need = max(3 * np.sqrt(2) * c.direction_sigma for c in cams)
        if self.tolerance < need:
            raise FieldError(
                "tolerance",
                f"{self.tolerance / ARCSEC:.3g}″ is below 3√2 σ = "
                f"{need / ARCSEC:.3g}″ of a measured inter-star angle (centroid "
                f"noise × pixel angle); true pairs would fail to match",
            )
        if index not in _INDEXES:
            raise FieldError("index", f"must be 'kvector' or 'brute', got {index!r}")
        widest = max(c.max_pair_angle for c in cams)
        if self.tolerance >= widest:
            raise FieldError(
                "tolerance",
                f"{self.tolerance / ARCSEC:.3g}″ is not below the widest inter-star angle of "
                f"a field, {widest / ARCSEC:.3g}″: every pair would match every pair",
            )
        self.cameras = tuple(cams)
        self.catalog = catalog.brighter_than(max(c.magnitude_limit for c in cams))
        max_angle = widest + self.tolerance
        self.index = _INDEXES[index](self.catalog, max_angle)

    def expected_candidates(self, false_stars: int = 0, missing_fraction: float = 0.0) -> float:
        """Expected candidate matches of one field of view (the size
        :func:`~flexsat.attitude.star_id.match_field` checks against
        :data:`flexsat.limits.MAX_PAIR_CANDIDATES`), estimated before any frame is made.

        The widest camera sees N Ω/4π of the N catalogue stars it detects (Ω = 4 arcsin
        sin²(F/2), the solid angle of a square field of full angle F), less the missing
        fraction, plus the false stars: k stars, C(k, 2) measured pairs. A measured pair
        matches the index's pairs within the tolerance of its angle: their mean count over the
        pairs of a 24 × 24 grid of points on the detector (stars, real or false, uniform on it).
        """
        cam = max(self.cameras, key=lambda c: c.field_of_view)
        half = 0.5 * cam.field_of_view
        solid_angle = 4.0 * np.arcsin(np.sin(half) ** 2)
        detected = np.count_nonzero(self.catalog.magnitudes <= cam.magnitude_limit)
        k = detected * solid_angle / (4 * np.pi) * (1.0 - missing_fraction) + false_stars
        ticks = (np.arange(24) + 0.5) * cam.n_pixels / 24
        grid = cam.directions(np.stack(np.meshgrid(ticks, ticks), -1).reshape(-1, 2))
        first, second = np.triu_indices(grid.shape[0], 1)
        angles = pair_angles(grid[first], grid[second])
        per_pair = self.index.count(angles - self.tolerance, angles + self.tolerance) / angles.size
        return 0.5 * k * max(k - 1.0, 0.0) * per_pair

    def expected_stars(self, missing_fraction: float = 0.0) -> FloatArray:
        """Mean catalogue stars in each camera's field (n_cameras,): N_c Ω_c/4π of the N_c
        catalogue stars camera c detects (Ω = 4 arcsin sin²(F/2), the solid angle of a square
        field of full angle F), less the missing fraction; the mean over attitudes uniform on
        SO(3), for a sky uniform on the sphere."""
        out = []
        for cam in self.cameras:
            solid_angle = 4.0 * np.arcsin(np.sin(0.5 * cam.field_of_view) ** 2)
            detected = np.count_nonzero(self.catalog.magnitudes <= cam.magnitude_limit)
            out.append(detected * solid_angle / (4 * np.pi) * (1.0 - missing_fraction))
        return np.array(out)

    @property
    def stars_needed(self) -> int:
        """Fewest stars in a field whose triangles can reach ``min_triplets``: the smallest
        k >= 3 with C(k, 3) >= min_triplets (a field of k stars has C(k, 3) triplets)."""
        k = max(3, int(np.cbrt(6.0 * self.min_triplets)))
        while k * (k - 1) * (k - 2) // 6 < self.min_triplets:
            k += 1
        return k

    def identifiable_fraction(
        self, missing_fraction: float = 0.0, stars: int | None = None
    ) -> float:
        r"""Probability that a random attitude puts at least :attr:`stars_needed` catalogue
        stars (3, one triangle, for up to one triplet) in at least ``min_fields`` fields: the
        star count of camera c Poisson with mean μ_c (:meth:`expected_stars`), the fields
        independent, p_c = P(N_c >= k) (for k = 3,
        :math:`1 - e^{-\mu_c}(1 + \mu_c + \mu_c^2/2)`), and the count of fields with p_c
        summed by the Poisson-binomial recursion. An upper bound on the identification rate
        (the matching itself can still fail). ``stars`` replaces :attr:`stars_needed`."""
        from scipy.stats import poisson

        mu = self.expected_stars(missing_fraction)
        p = poisson.sf((self.stars_needed if stars is None else stars) - 1, mu)
        fields = np.zeros(len(p) + 1)  # fields[j]: probability that j fields have enough
        fields[0] = 1.0
        for pc in np.clip(p, 0.0, 1.0):
            fields[1:] = fields[1:] * (1 - pc) + fields[:-1] * pc
            fields[0] *= 1 - pc
        return float(fields[self.min_fields :].sum())

    def observe(
        self,
        attitude: npt.ArrayLike,
        rng: np.random.Generator,
        false_stars: int = 0,
        missing_fraction: float = 0.0,
    ) -> list[StarFrame]:
        """One frame per camera at the true attitude C_bn (:meth:`StarCamera.observe`)."""
        return [
            cam.observe(attitude, self.catalog, rng, c, false_stars, missing_fraction)
            for c, cam in enumerate(self.cameras)
        ]

    def identify(self, frames: Sequence[StarFrame]) -> Identification:
        """Lost-in-space identification of simultaneous frames
        (:func:`~flexsat.attitude.star_id.identify_frames`)."""
        return identify_frames(
            frames, self.cameras, self.index, self.tolerance, self.min_triplets, self.min_fields
        )


def score(ident: Identification, frames: Sequence[StarFrame]) -> tuple[bool, int]:
    """(correct, wrong stars): an accepted identification is correct when every star it kept
    is the true one; ``wrong`` counts the kept stars that are not (false stars included)."""
    if not ident.accepted:
        return False, 0
    wrong = sum(
        int(np.count_nonzero((fm.matches >= 0) & (fm.matches != f.truth)))
        for fm, f in zip(ident.fields, frames)
    )
    return wrong == 0, wrong


@dataclass(frozen=True)
class MonteCarloResult:
    """Per attitude: ``accepted``, ``correct`` (accepted and every kept star right),
    ``wrong_accepted`` (accepted with a wrong star), ``errors`` (n, 3) body-axis error angles
    (rad, NaN when rejected), ``sigmas`` (n, 3) QUEST 1σ per axis (rad), ``n_stars`` kept,
    ``triplets`` (n, n_cameras); the first attitude's frames and identification for plots."""

    attitudes: FloatArray
    accepted: npt.NDArray[np.bool_]
    correct: npt.NDArray[np.bool_]
    wrong_accepted: npt.NDArray[np.bool_]
    errors: FloatArray
    sigmas: FloatArray
    nees: FloatArray
    n_stars: npt.NDArray[np.int_]
    triplets: npt.NDArray[np.int_]
    example_frames: list[StarFrame]
    example: Identification

    @property
    def identification_rate(self) -> float:
        return float(np.mean(self.correct))

    @property
    def error_std(self) -> FloatArray:
        """1σ of the error angles per body axis over the accepted attitudes, rad."""
        return np.nanstd(self.errors, axis=0)


def check_field_load(tracker: StarTracker, false_stars: int, missing_fraction: float) -> None:
    """Refuse, before any frame is made, false stars that would give one field more candidate
    matches than :data:`flexsat.limits.MAX_PAIR_CANDIDATES`
    (:meth:`StarTracker.expected_candidates`).

    Raises
    ------
    flexsat.input_checks.FieldError
        Naming ``tolerance`` when the real stars alone exceed the limit, else ``false_stars``.
    """
    bare = tracker.expected_candidates(0, missing_fraction)
    if bare > limits.MAX_PAIR_CANDIDATES:  # the real stars alone: the tolerance is too wide
        raise FieldError(
            "tolerance",
            f"{tracker.tolerance / ARCSEC:.3g}″ would make about {bare:.3g} candidate catalogue "
            f"matches per field from the real stars alone, above the limit "
            f"{limits.MAX_PAIR_CANDIDATES:,} (flexsat.limits.MAX_PAIR_CANDIDATES): the "
            "identification would crawl; a smaller tolerance",
        )
    expected = tracker.expected_candidates(false_stars, missing_fraction)
    if expected > limits.MAX_PAIR_CANDIDATES:
        raise FieldError(
            "false_stars",
            f"{false_stars} per field would make about {expected:.3g} candidate catalogue "
            f"matches per field, above the limit {limits.MAX_PAIR_CANDIDATES:,} "
            f"(flexsat.limits.MAX_PAIR_CANDIDATES): the identification would crawl; fewer "
            f"false stars or a smaller tolerance",
        )


#: fewest expected identifiable attitudes of a run (:func:`check_identifiable`): below it the
#: run would, with more than 99 % probability, identify nothing
MIN_IDENTIFIABLE = 0.01


def check_identifiable(tracker: StarTracker, attitudes: int, missing_fraction: float) -> None:
    """Refuse, before any frame is made, a run that can only identify nothing: fewer than
    :data:`MIN_IDENTIFIABLE` of its ``attitudes`` expected to show >= 3 catalogue stars in
    ``min_fields`` fields (:meth:`StarTracker.identifiable_fraction`): an empty or too faint
    catalogue, a field of view too small for the sky, nearly every star missing.

    Raises
    ------
    flexsat.input_checks.FieldError
        Naming ``missing_fraction`` when the stars are there but dropped, ``min_triplets`` when
        no field can hold the stars its triplets need, else ``cameras``.
    """
    if attitudes * tracker.identifiable_fraction(0.0, stars=3) < MIN_IDENTIFIABLE:
        missing_fraction = 0.0  # the sky and the cameras alone identify nothing
        field = "cameras"
    elif attitudes * tracker.identifiable_fraction() < MIN_IDENTIFIABLE:
        missing_fraction = 0.0  # no field holds the stars of that many triplets
        field = "min_triplets"
    elif attitudes * tracker.identifiable_fraction(missing_fraction) < MIN_IDENTIFIABLE:
        field = "missing_fraction"
    else:
        return
    expected = attitudes * tracker.identifiable_fraction(missing_fraction)
    stars = tracker.expected_stars(missing_fraction)
    raise FieldError(
        field,
        f"the fields of view hold on average {np.array2string(stars, precision=3)} catalogue "
        f"stars ({len(tracker.catalog)} in the catalogue, fraction {missing_fraction:g} "
        "missing), so "
        f"about {expected:.3g} of the {attitudes} attitudes could show the "
        f"{tracker.stars_needed} stars in {tracker.min_fields} fields an identification needs "
        f"({tracker.min_triplets} triplets a field): the run could only report no data; a "
        "wider field, a fainter magnitude limit, fewer missing stars or fewer triplets",
    )


def monte_carlo(
    tracker: StarTracker,
    n: int = 1000,
    seed: int | np.random.Generator = 0,
    false_stars: int = 0,
    missing_fraction: float = 0.0,
) -> MonteCarloResult:
    """Identify ``n`` seeded random attitudes (module docstring). ``nees`` is δθᵀP⁻¹δθ per
    accepted attitude (χ² with 3 degrees of freedom when the covariance is right)."""
    n = require_count(n, "n")
    check_field_load(tracker, false_stars, missing_fraction)
    check_identifiable(tracker, n, missing_fraction)
    rng = np.random.default_rng(seed)
    att = random_attitudes(n, rng)
    n_cam = len(tracker.cameras)
    acc, cor, wrong = np.zeros(n, bool), np.zeros(n, bool), np.zeros(n, bool)
    err, sig = np.full((n, 3), np.nan), np.full((n, 3), np.nan)
    nees, nst, trip = np.full(n, np.nan), np.zeros(n, int), np.zeros((n, n_cam), int)
    example: tuple[list[StarFrame], Identification] | None = None
    for k in range(n):
        frames = tracker.observe(att[k], rng, false_stars, missing_fraction)
        ident = tracker.identify(frames)
        if example is None:
            example = (frames, ident)
        ok, bad = score(ident, frames)
        acc[k], cor[k], wrong[k] = ident.accepted, ok, bad > 0
        nst[k] = ident.n_stars
        trip[k] = [fm.triplets for fm in ident.fields]
        if ident.accepted:
            # an accepted identification carries its fitted attitude and covariance
            assert ident.attitude is not None and ident.covariance is not None
            e = rotation_error(ident.attitude, att[k])
            err[k], sig[k] = e, np.sqrt(np.diag(ident.covariance))
            nees[k] = e @ np.linalg.solve(ident.covariance, e)
    assert example is not None  # n >= 1 (random_attitudes checks it)
    return MonteCarloResult(att, acc, cor, wrong, err, sig, nees, nst, trip, example[0], example[1])
