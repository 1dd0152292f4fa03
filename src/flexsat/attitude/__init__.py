"""Attitude determination from star images: a star catalogue (Hipparcos files or a synthetic
sky), a pinhole star camera, star-pattern identification (pair-angle index by k-vector or k-d
tree, triangle voting), the attitude fit (Davenport's q-method with the QUEST covariance) and a
star tracker that chains them over frames (:class:`StarTracker`, :func:`monte_carlo`).

It shares only the pinhole camera model with :mod:`flexsat.identify` (photogrammetry)."""

from flexsat.attitude.fit import q_method, quest_covariance
from flexsat.attitude.pair_index import BruteForceIndex, KVectorIndex
from flexsat.attitude.star_camera import StarCamera, StarFrame
from flexsat.attitude.star_catalog import StarCatalog, load_hipparcos, synthetic_sky
from flexsat.attitude.star_id import Identification, identify_frames, match_field
from flexsat.attitude.star_tracker import StarTracker, monte_carlo

__all__ = [
    "BruteForceIndex",
    "Identification",
    "KVectorIndex",
    "StarCamera",
    "StarCatalog",
    "StarFrame",
    "StarTracker",
    "identify_frames",
    "load_hipparcos",
    "match_field",
    "monte_carlo",
    "q_method",
    "quest_covariance",
    "synthetic_sky",
]
