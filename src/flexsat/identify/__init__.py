"""System identification from vibration tests: test data, synthetic tests, realization (ERA,
OKID), Creamer-Junkins structural identification and model update, and stereo triangulation
(camera model, calibration, dynamic triangulation), and star-pattern identification for a star
tracker (catalogue, pinhole star camera, k-vector, q-method)."""

from flexsat.identify.era import (
    bootstrap_uncertainty,
    Realization,
    era,
    era_dc,
    mac,
    markov_from_frf,
    markov_parameters,
    noise_damping_sweep,
    okid,
)
from flexsat.identify.excitation import (
    Excitation,
    harmonic_shaker,
    impulse_hammer,
    random_force,
    simulate_test,
    torque_history,
)
from flexsat.identify.measurements import CHANNEL_KINDS, Channel, Measurement
from flexsat.identify.photogrammetry import (
    CalibrationResult,
    Camera,
    calibrate,
    calibration_counts,
    project,
    simulate_centroids,
    triangulate,
)
from flexsat.identify.differential_correction import (
    CorrectionData,
    DifferentialCorrection,
    differential_correction,
)
from flexsat.identify.attitude_fit import q_method, quest_covariance
from flexsat.identify.pair_index import BruteForceIndex, KVectorIndex
from flexsat.identify.star_camera import StarCamera, StarFrame
from flexsat.identify.star_catalog import StarCatalog, load_hipparcos, synthetic_sky
from flexsat.identify.star_id import Identification, identify_frames, match_field
from flexsat.identify.star_tracker import StarTracker, monte_carlo
from flexsat.identify.structural import (
    SubstructureModel,
    identify_damping,
    identify_undamped,
    modal_energy_distribution,
    substructures_from_builder,
    update_model,
)

__all__ = [
    "BruteForceIndex", "Identification", "KVectorIndex", "StarCamera", "StarCatalog",
    "StarFrame", "StarTracker", "identify_frames", "load_hipparcos", "match_field",
    "monte_carlo", "q_method", "quest_covariance", "synthetic_sky",
    "CHANNEL_KINDS",
    "CalibrationResult",
    "Camera",
    "Channel",
    "CorrectionData",
    "DifferentialCorrection",
    "Excitation",
    "Measurement",
    "Realization",
    "bootstrap_uncertainty",
    "SubstructureModel",
    "calibrate",
    "calibration_counts",
    "differential_correction",
    "era",
    "era_dc",
    "harmonic_shaker",
    "identify_damping",
    "identify_undamped",
    "impulse_hammer",
    "mac",
    "markov_from_frf",
    "markov_parameters",
    "modal_energy_distribution",
    "noise_damping_sweep",
    "okid",
    "project",
    "random_force",
    "simulate_centroids",
    "simulate_test",
    "substructures_from_builder",
    "torque_history",
    "triangulate",
    "update_model",
]
