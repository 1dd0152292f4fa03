"""Stereo photogrammetry (Junkins, Pollock & Rahman 1990, Att. 6 and 8): the collinearity
camera model (:mod:`~flexsat.identify.photogrammetry.camera`), static calibration
(:mod:`~flexsat.identify.photogrammetry.calibration`) and dynamic triangulation
(:mod:`~flexsat.identify.photogrammetry.triangulation`)."""

from flexsat.identify.photogrammetry.calibration import (
    DEFAULT_FREE,
    CalibrationResult,
    calibrate,
    calibration_counts,
)
from flexsat.identify.photogrammetry.camera import (
    CAMERA_PARAMETERS,
    FIELD_RATE_HZ,
    FIELD_SIZE_PX,
    Camera,
    euler_angles,
    look_at,
    project,
    rotation_matrix,
    simulate_centroids,
)
from flexsat.identify.photogrammetry.triangulation import triangulate

__all__ = [
    "look_at",
    "Camera",
    "CalibrationResult",
    "CAMERA_PARAMETERS",
    "DEFAULT_FREE",
    "FIELD_SIZE_PX",
    "FIELD_RATE_HZ",
    "rotation_matrix",
    "euler_angles",
    "project",
    "simulate_centroids",
    "calibration_counts",
    "calibrate",
    "triangulate",
]
