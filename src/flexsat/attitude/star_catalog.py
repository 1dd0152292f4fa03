r"""Star catalogues for star-pattern identification (Junkins, Pollock & Rahman
1990, §2.3.4): a seeded synthetic sky and a loader for the Hipparcos main catalogue.

A catalogue holds, per star, an identifier, a visual magnitude and a unit direction in the
inertial (ICRS) frame, ``r = [cos δ cos α, cos δ sin α, sin δ]``.

**Synthetic sky.** Stars are uniform on the sphere (z = sin δ uniform on [−1, 1], α uniform on
[0, 2π)) with the cumulative magnitude distribution of the real sky,

.. math::

    \log_{10} N(<m) = 0.5\,(m - 6.5) + \log_{10} N_{6.5},

i.e. about ×3.16 stars per magnitude (the Seares–van Rhijn star-count slope near the
galactic mean, Allen's *Astrophysical Quantities* §20), calibrated to
:data:`STARS_BRIGHTER_THAN_6_5` = 5,000 stars brighter than m = 6.5 (issue 14's calibration;
the real sky has ≈ 5,000 stars to V ≈ 6.0 and the Yale Bright Star catalogue 9,110 to ≈ 6.5,
so the default synthetic sky is somewhat sparser: fewer stars per field, the harder case for
identification). The magnitudes are drawn by inverting N(<m): m = m_lim + 2 log10(U), U
uniform on (0, 1], clipped at the bright end at :data:`BRIGHTEST_MAGNITUDE` (Sirius, V = −1.46).

**Hipparcos.** ``hip_main.dat`` (ESA 1997, SP-1200, CDS catalogue I/239) is one star per line,
fields separated by ``|``: field H1 (index 1) is the HIP number, H5 the Johnson V magnitude,
H8 and H9 the right ascension and declination in degrees (ICRS, epoch J1991.25). Lines with a
blank position or magnitude (263 stars have no astrometric solution) are skipped; proper motion
is ignored (≤ 10″ per decade for all but a few hundred stars, below the identification
tolerance over a mission's decade; propagate the catalogue yourself for tighter use).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from flexsat import limits
from flexsat.input_checks import FieldError, require_count, require_finite
from flexsat.units import FloatArray

__all__ = [
    "StarCatalog",
    "synthetic_sky",
    "load_hipparcos",
    "STARS_BRIGHTER_THAN_6_5",
    "BRIGHTEST_MAGNITUDE",
    "MIN_STARS",
    "HIPPARCOS_FIELDS",
]

#: naked-eye star count the synthetic sky is calibrated to (module docstring)
STARS_BRIGHTER_THAN_6_5 = 5000
#: brightest star of the sky (Sirius, V = −1.46): the synthetic magnitudes stop there
BRIGHTEST_MAGNITUDE = -1.46
#: a catalogue needs one triangle of stars to identify anything (three inter-star angles)
MIN_STARS = 3
#: 0-based indices of the fields read from a ``|``-separated hip_main.dat line (HIP, Vmag,
#: RAdeg, DEdeg: fields H1, H5, H8, H9 of the ReadMe of CDS I/239)
HIPPARCOS_FIELDS = {"hip": 1, "vmag": 5, "ra_deg": 8, "dec_deg": 9}


def _directions(ra: npt.ArrayLike, dec: npt.ArrayLike) -> FloatArray:
    cd = np.cos(dec)
    return np.stack([cd * np.cos(ra), cd * np.sin(ra), np.sin(dec)], -1)


@dataclass(frozen=True)
class StarCatalog:
    """Stars as arrays: ``ids`` (n,), ``magnitudes`` (n,), inertial unit ``vectors`` (n, 3).

    Raises
    ------
    ValueError
        When fewer than :data:`MIN_STARS` stars are given (no triangle to match), or the arrays
        disagree in length or hold non-finite values.
    """

    ids: npt.NDArray[np.int_]
    magnitudes: FloatArray
    vectors: FloatArray
    source: str = "user"

    def __post_init__(self) -> None:
        ids = np.asarray(self.ids).reshape(-1)
        mags = require_finite(self.magnitudes, "magnitudes").reshape(-1)
        vec = require_finite(self.vectors, "vectors")
        if vec.ndim != 2 or vec.shape[1] != 3:
            raise FieldError("vectors", f"must have shape (n_stars, 3), got {vec.shape}")
        if not (ids.size == mags.size == vec.shape[0]):
            raise FieldError(
                "catalog",
                f"ids ({ids.size}), magnitudes ({mags.size}) and vectors "
                f"({vec.shape[0]}) must have one entry per star",
            )
        if ids.size < MIN_STARS:
            raise FieldError(
                "catalog",
                f"must hold at least {MIN_STARS} stars (one triangle of "
                f"inter-star angles), got {ids.size}",
            )
        norms = np.linalg.norm(vec, axis=1)
        if np.any(np.abs(norms - 1) > 1e-6):
            raise FieldError("vectors", "must be unit directions (|r| = 1 to 1e-6)")
        object.__setattr__(self, "ids", ids)
        object.__setattr__(self, "magnitudes", mags)
        object.__setattr__(self, "vectors", vec / norms[:, None])

    def __len__(self) -> int:
        return self.ids.size

    def brighter_than(self, magnitude_limit: float) -> StarCatalog:
        """The stars with m <= ``magnitude_limit`` (the camera's limit).

        Raises
        ------
        ValueError
            When fewer than :data:`MIN_STARS` stars remain.
        """
        limit = float(require_finite(magnitude_limit, "magnitude_limit"))
        keep = self.magnitudes <= limit
        if keep.sum() < MIN_STARS:
            raise FieldError(
                "magnitude_limit",
                f"only {int(keep.sum())} stars are brighter than "
                f"{limit:g}; a catalogue needs at least {MIN_STARS}",
            )
        return StarCatalog(self.ids[keep], self.magnitudes[keep], self.vectors[keep], self.source)


def synthetic_sky(
    magnitude_limit: float = 6.5,
    seed: int = 0,
    stars_brighter_than_6_5: int = STARS_BRIGHTER_THAN_6_5,
) -> StarCatalog:
    r"""Seeded synthetic sky to ``magnitude_limit`` (module docstring): ``N(<m_lim) =
    N_6.5 · 10^{0.5 (m_lim − 6.5)}`` stars, uniform on the sphere.

    Raises
    ------
    ValueError
        When the limit leaves fewer than :data:`MIN_STARS` stars.
    """
    limit = float(require_finite(magnitude_limit, "magnitude_limit"))
    n65 = require_count(stars_brighter_than_6_5, "stars_brighter_than_6_5")
    # the count is checked on its logarithm, before 10^x can overflow or the sky is drawn
    log_n = np.log10(n65) + 0.5 * (limit - 6.5)
    if log_n > np.log10(limits.MAX_CATALOG_STARS):
        raise FieldError(
            "magnitude_limit",
            f"{limit:g} gives a synthetic sky of about 10^{log_n:.3g} stars, above the limit "
            f"{limits.MAX_CATALOG_STARS:,} (flexsat.limits.MAX_CATALOG_STARS); star cameras "
            f"detect to about m = 7-9",
        )
    n = int(round(n65 * 10 ** (0.5 * (limit - 6.5))))
    if n < MIN_STARS or limit <= BRIGHTEST_MAGNITUDE:
        raise FieldError(
            "magnitude_limit",
            f"{limit:g} gives {n} synthetic stars; a catalogue needs at least {MIN_STARS}",
        )
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1.0, 1.0, n)
    ra = rng.uniform(0.0, 2 * np.pi, n)
    u = 1.0 - rng.uniform(0.0, 1.0, n)  # (0, 1]: log10 finite
    mags = np.maximum(limit + 2.0 * np.log10(u), BRIGHTEST_MAGNITUDE)
    return StarCatalog(
        np.arange(1, n + 1),
        mags,
        _directions(ra, np.arcsin(z)),
        f"synthetic sky (seed {seed}, m <= {limit:g})",
    )


def load_hipparcos(path: str | Path, magnitude_limit: float | None = None) -> StarCatalog:
    """Stars of a user-supplied Hipparcos main catalogue file (``hip_main.dat``, module
    docstring), optionally only those with V <= ``magnitude_limit``.

    Raises
    ------
    ValueError
        For a missing file, a line with too few ``|`` fields or an unreadable number (naming the
        line), or fewer than :data:`MIN_STARS` usable stars.
    """
    p = Path(path)
    if not p.is_file():
        raise FieldError("path", f"no Hipparcos catalogue file at {str(p)!r}")
    limit = (
        None
        if magnitude_limit is None
        else float(require_finite(magnitude_limit, "magnitude_limit"))
    )
    ids: list[int] = []
    mags: list[float] = []
    ra: list[float] = []
    dec: list[float] = []
    need = max(HIPPARCOS_FIELDS.values()) + 1
    with p.open(encoding="ascii", errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            if not line.strip():
                continue
            f = line.split("|")
            if len(f) < need:
                raise ValueError(
                    f"{p.name}:{lineno}: a hip_main.dat line has at least {need} "
                    f"'|'-separated fields (HIP, Vmag, RAdeg, DEdeg at 1, 5, 8, 9), "
                    f"got {len(f)}"
                )
            raw = {k: f[i].strip() for k, i in HIPPARCOS_FIELDS.items()}
            if not (raw["vmag"] and raw["ra_deg"] and raw["dec_deg"]):
                continue  # no astrometric solution or no magnitude: not a usable star
            try:
                values = {k: float(v) for k, v in raw.items()}
            except ValueError:
                raise ValueError(
                    f"{p.name}:{lineno}: HIP, Vmag, RAdeg and DEdeg must be numbers, got {raw}"
                ) from None
            if not (0 <= values["ra_deg"] < 360 + 1e-9 and abs(values["dec_deg"]) <= 90):
                raise ValueError(
                    f"{p.name}:{lineno}: RAdeg must lie in [0, 360) and DEdeg in "
                    f"[-90, 90], got {values['ra_deg']}, {values['dec_deg']}"
                )
            if limit is not None and values["vmag"] > limit:
                continue
            ids.append(int(values["hip"]))
            mags.append(values["vmag"])
            ra.append(values["ra_deg"])
            dec.append(values["dec_deg"])
    if len(ids) < MIN_STARS:
        raise FieldError(
            "catalog",
            f"{p.name} holds {len(ids)} usable stars"
            f"{'' if limit is None else f' brighter than {limit:g}'}; a catalogue "
            f"needs at least {MIN_STARS} (one triangle of inter-star angles)",
        )
    vec = _directions(np.radians(ra), np.radians(dec))
    return StarCatalog(np.array(ids), np.array(mags), vec, f"Hipparcos ({p.name})")
