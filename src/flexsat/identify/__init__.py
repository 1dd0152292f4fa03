"""System identification from vibration tests: test data, excitations, realization (ERA,
OKID), Creamer-Junkins structural identification and model update, and stereo triangulation
(camera model, calibration, dynamic triangulation), the frontal-assault FRF fit and video
targets (rendered frames, blob extraction, sub-pixel centroids). Star identification and
attitude fitting are in :mod:`flexsat.attitude`."""

from flexsat.identify.differential_correction import (
    CorrectionData,
    DifferentialCorrection,
    differential_correction,
)
from flexsat.identify.era import Realization, bootstrap_uncertainty, era, era_dc, mac
from flexsat.identify.excitation import (
    Excitation,
    harmonic_shaker,
    impulse_hammer,
    random_force,
    torque_history,
)
from flexsat.identify.frontal_assault import FRFData, FrontalAssaultModel, frontal_assault
from flexsat.identify.markov import markov_from_frf, markov_parameters, okid
from flexsat.identify.measurements import STRUCTURAL_KINDS, Channel, Measurement, uff_direction
from flexsat.identify.photogrammetry import (
    CalibrationResult,
    Camera,
    calibrate,
    calibration_counts,
    project,
    simulate_centroids,
    triangulate,
)
from flexsat.identify.structural import (
    SubstructureModel,
    identify_damping,
    identify_undamped,
    modal_energy_distribution,
    substructures_from_builder,
    update_model,
)
from flexsat.identify.video_targets import (
    BlobSet,
    FrameSpec,
    extract_blobs,
    measure_views,
    render_frame,
)

__all__ = [
    "STRUCTURAL_KINDS",
    "BlobSet",
    "FRFData",
    "FrameSpec",
    "FrontalAssaultModel",
    "extract_blobs",
    "frontal_assault",
    "measure_views",
    "render_frame",
    "uff_direction",
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
    "okid",
    "project",
    "random_force",
    "simulate_centroids",
    "substructures_from_builder",
    "torque_history",
    "triangulate",
    "update_model",
]

# the synthetic tests run on the engine (flexsat.sim.vibration_test.simulate_test), a layer above
