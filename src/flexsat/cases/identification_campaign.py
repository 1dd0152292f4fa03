r"""An end-to-end identification campaign on a substructured finite-element case.

The loop of the Texas A&M grid experiments (Att. 6 and 8 of Junkins, Pollock & Rahman 1990), run on
a simulated "true" structure:

The true structure is the case's finite-element model with all its modes; the sampled tests
have analog anti-aliasing filters on every channel (``anti_alias`` × the sample rate), as a
real acquisition front end has, so modes above the band do not fold into it and the H1 FRF is
the continuous one.

1. **Hammer test** (free vibration, Att. 6 Fig. 2): an impulse at one node, recorded by strain
   gauges and accelerometers with noise; Markov parameters and ERA give frequencies, damping
   ratios and their uncertainty (first-order, or by parametric bootstrap with
   ``bootstrap_samples``; the first-order one overstates the actual scatter 20-40× here).
2. **Video test** (Att. 6 Fig. 3, §1.5–1.7): the structure at rest is imaged by two cameras and
   the cameras are calibrated from the targets' a-priori positions (Att. 6 Eq. 30; the principal
   point is held at the detector centre, because images of one plane of targets fix only a
   homography, 8 numbers, per camera); a second hammer blow is filmed at the field rate, every
   field is triangulated, and ERA on the target z displacements gives the mode shapes.
3. **Reaction-wheel test** (Att. 6 "Frequency Response Functions"): random torques from the
   wheels, recorded by the strain
   gauges; the H1 FRFs and an OKID realization (arbitrary inputs).
4. **Model update**, ``update`` =
   ``"creamer_junkins"`` (Att. 7 Eqs. 1–9 and 24): the substructure stiffness scalings from the
   ERA frequencies (modes paired by the video MAC), then Rayleigh damping scalings from the
   measured eigenvalue real parts; or ``"differential_correction"`` (Att. 6 Eqs. 3–13): both at
   once from the frequencies, the damping ratios and the H1 FRF points of the wheel test.  The
   mass matrix is held: frequencies and shapes fix only the stiffness-to-mass ratio (Att. 6
   scales its shapes with the analytical mass matrix for the same reason).

The a-priori model starts from Att. 6 Eq. 15 proportional damping ``C = 2 zeta_1 omega_1 M``.
Everything is seeded: the same configuration gives the same result.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
import numpy.typing as npt

from flexsat.dynamics.plant import Channel
from flexsat.identify.differential_correction import CorrectionData, differential_correction
from flexsat.identify.era import Realization, bootstrap_uncertainty, era, mac
from flexsat.identify.excitation import Excitation, impulse_hammer, random_force
from flexsat.identify.markov import markov_parameters, okid
from flexsat.identify.measurements import Measurement
from flexsat.identify.photogrammetry import (
    CAMERA_PARAMETERS,
    CalibrationResult,
    Camera,
    calibrate,
    look_at,
    simulate_centroids,
    triangulate,
)
from flexsat.identify.spectral import FRFEstimate, estimate_frf, frequency_response
from flexsat.identify.structural import (
    SubstructureModel,
    identify_damping,
    identify_undamped,
    substructures_from_builder,
)
from flexsat.input_checks import FieldError
from flexsat.sim.vibration_test import simulate_test
from flexsat.structures.fem import Assembly, FEModes, Structure
from flexsat.structures.modal_model import ModalModel
from flexsat.units import FloatArray

__all__ = [
    "CameraRig",
    "CampaignConfig",
    "CampaignResult",
    "IDENTIFY_STEPS",
    "SIMULATE_STEPS",
    "SubstructuredCase",
    "TestRecords",
    "identify_and_update",
    "run_campaign",
    "simulate_records",
]

#: the steps :func:`simulate_records` and :func:`identify_and_update` announce to their
#: ``progress`` callback, in order (a progress bar's length)
SIMULATE_STEPS = ("hammer test", "camera calibration and video test", "reaction-wheel test")
IDENTIFY_STEPS = (
    "hammer test: ERA",
    "video test: ERA",
    "reaction-wheel test: FRF and OKID",
    "model update",
)

#: model-update methods: Att. 6 (free and forced response together) or Att. 7 (frequencies, then
#: damping from the eigenvalue real parts)
UPDATE_METHODS = ("differential_correction", "creamer_junkins")
#: FRF points closer than this (relative) to a resonance are not used: near a resonance the fit
#: can lock onto a wrong mode (docs/identification.md)
RESONANCE_CLEARANCE = 0.08
#: relative misfit allowed to the damping ratios in the Att. 6 fit: two Rayleigh coefficients
#: cannot follow a measured pattern such as Att. 6 Table 1 (0.006, 0.005, 0.011, 0.006, 0.013),
#: and with the ERA SDs alone that misfit would be absorbed by the stiffness scalings (the
#: damping ratio of a Rayleigh model moves with the frequency)
DAMPING_FORM_ERROR = 0.3

#: camera parameters calibrated in the video test (principal point held; module docstring)
VIDEO_FREE = ("xc", "yc", "zc", "a1", "a2", "a3", "f")


class SubstructuredCase(Protocol):
    """A case the campaign tests and updates (e.g. :class:`flexsat.cases.tamu_grid.
    TamuGridCase`): named stiffness substructures and the finite-element structure with a
    factor on each."""

    @property
    def substructures(self) -> Sequence[str]:
        """The substructures' names."""
        ...

    def structure(self, *, stiffness_scale: Mapping[str, float] | None = None) -> Structure:
        """The structure, each named substructure's stiffness scaled (default 1)."""
        ...


@dataclass(frozen=True)
class CameraRig:
    """Two or more cameras aimed at points of the structure (SI).

    ``positions`` and ``aims`` are (M, 3); ``focal_length`` and ``pixel_size`` in m (NAC V-14B:
    2/3" CCD, 320 × 244 pixels of about 27 µm); ``noise_px`` the centroid noise in pixels;
    ``position_error`` and ``angle_error`` the standard deviations of the initial camera guess
    (m, rad); ``static_fields`` the fields averaged for the calibration image.
    """

    positions: tuple[Sequence[float] | FloatArray, ...]
    aims: tuple[Sequence[float] | FloatArray, ...]
    focal_length: float = 0.008
    pixel_size: float = 27e-6
    noise_px: float = 0.05
    quantize: bool = False
    position_error: float = 0.05
    angle_error: float = 0.02
    static_fields: int = 50

    def cameras(self) -> list[Camera]:
        """The cameras (Att. 8 conventions: 3-2-1 Euler angles, "-f"), aimed at ``aims``."""
        return [
            Camera(position=pos, angles=look_at(pos, aim), f=self.focal_length)
            for pos, aim in zip(self.positions, self.aims)
        ]


@dataclass(frozen=True)
class CampaignConfig:
    """What to test and how (SI).  See :func:`run_campaign`."""

    truth_damping: tuple[float, ...] = (0.00603, 0.00489, 0.01105, 0.00596, 0.01293)
    other_damping: float = 0.01
    truth_modes: int | None = None
    a_priori_scale: dict[str, float] = field(default_factory=dict)
    a_priori_damping: float = 0.006
    strain_gauges: tuple[tuple[int, int, str], ...] = ()  # (node_a, node_b, axis)
    accelerometers: tuple[tuple[int, str], ...] = ()  # (node, direction)
    targets: tuple[int, ...] = ()  # node ids
    hammer_node: int = 1
    hammer_direction: str = "z"
    hammer_impulse: float = 0.5  # N s
    hammer_duration: float = 20.0
    sample_rate: float = 200.0
    noise: float = 0.01
    video_impulse: float = 0.3  # N s
    video_duration: float = 4.5
    field_rate: float = 200.0
    target_sigma: float = 1e-3
    rig: CameraRig | None = None
    wheel_nodes: tuple[int, ...] = ()
    wheel_axes: tuple[str, ...] = ()
    wheel_torque_rms: float = 0.05
    # true / nominal, one per wheel; () = known exactly
    wheel_torque_constants: tuple[float, ...] = ()
    identify_torque_constants: bool = False  # also without known true values (measured data)
    wheel_duration: float = 300.0
    wheel_sample_rate: float = 50.0
    frf_segment: int = 2000
    band: float = 10.0
    era_order: int = 80
    update: str = "differential_correction"
    frf_step: float = 0.2
    anti_alias: float = 0.4
    bootstrap_samples: int = 10
    seed: int = 0

    def __post_init__(self) -> None:
        if self.update not in UPDATE_METHODS:
            raise FieldError("update", f"must be one of {UPDATE_METHODS}, got {self.update!r}")
        k = self.wheel_torque_constants
        if k and (len(k) != len(self.wheel_nodes) or not all(np.isfinite(k)) or min(k) <= 0):
            raise FieldError(
                "wheel_torque_constants",
                f"one factor > 0 per wheel ({len(self.wheel_nodes)}), got {k!r}",
            )
        if (k or self.identify_torque_constants) and self.update != "differential_correction":
            raise FieldError(
                "wheel_torque_constants",
                "identifying the wheels' torque constants "
                "needs the FRF, i.e. update 'differential_correction'",
            )


@dataclass(frozen=True)
class CampaignResult:
    """Everything measured, identified and updated (see :func:`run_campaign`).

    Frequencies in Hz.  ``modes`` pairs each identified mode with a model mode (0-based
    ``model_index``); ``scalings`` gives, per substructure, the a-priori factor on the nominal
    stiffness (the case's; the truth of a simulation), the identified scaling ``p`` of the
    a-priori block with its standard deviation, and the updated factor on the nominal
    (``a_priori * p``; in a simulation 1 = recovered).  ``update`` names
    the method, the FRF points it used, its iterations and whether it converged.
    ``wheel_gains`` (when the torque constants are identified): per wheel the delivered over
    the commanded torque, true (a simulation's ``wheel_torque_constants``, else None) and
    identified with its SD (Att. 6 Eq. 7).
    ``frf_updated`` is relative to the commanded torque, like the measurement.
    """

    substructures: tuple[str, ...]
    modes: dict[str, list[Any]]
    scalings: dict[str, dict[str, float]]
    wheel_gains: dict[str, dict[str, Any]]
    update: dict[str, Any]
    damping_scalings: np.ndarray
    mac_a_priori: np.ndarray
    mac_updated: np.ndarray
    frf_frequencies: np.ndarray
    frf_measured: np.ndarray
    frf_coherence: np.ndarray
    frf_a_priori: np.ndarray
    frf_updated: np.ndarray
    frf_outputs: tuple[str, ...]
    frf_inputs: tuple[str, ...]
    video_shapes: np.ndarray
    target_nodes: tuple[int, ...]
    calibration: dict[str, Any]
    triangulation: dict[str, Any]
    hammer_realization: Realization = field(repr=False)
    video_realization: Realization | None = field(repr=False)
    okid_realization: Realization = field(repr=False)


# ------------------------------------------------------------------------------------------------
def _modal_model(
    assembly: Assembly, omegas: np.ndarray, shapes: np.ndarray, damping: np.ndarray
) -> ModalModel:
    return ModalModel.from_fe(
        FEModes(omegas, shapes, assembly), damping=damping, boundary="cantilevered"
    )


def _blow(node: int, direction: str, impulse: float, rate: float) -> Excitation:
    """A one-sample half-sine hammer blow of the given impulse (N s): peak pi I / (2 dt)."""
    return impulse_hammer(node, direction, np.pi * impulse * rate / 2.0)


def _truth_damping(cfg: CampaignConfig, n: int) -> np.ndarray:
    """Modal damping of the truth: ``truth_damping`` for the first modes, then
    ``other_damping``."""
    z = np.full(n, float(cfg.other_damping))
    k = min(n, len(cfg.truth_damping))
    z[:k] = cfg.truth_damping[:k]
    return z


def _select(real: Realization, band: float, min_mpc: float = 0.5) -> np.ndarray:
    """Indices of the physical modes in (0, band] Hz: positive damping below 20 %, consistent
    in time (EMAC) and mono-phase enough (MPC) to be a real normal mode."""
    f, z = real.frequencies_hz, real.damping
    ok = (f > 0) & (f <= band) & (z > 0) & (z < 0.2) & (real.emac > 0.5) & (real.mpc > min_mpc)
    return np.flatnonzero(ok)


def _real_shapes(shapes: np.ndarray) -> np.ndarray:
    """Real normal-mode shapes from complex ERA shapes (each already rotated to its largest
    component real)."""
    return shapes.real / np.linalg.norm(shapes.real, axis=0, keepdims=True)


def _pair(
    f_ident: np.ndarray, f_model: np.ndarray, mac_matrix: np.ndarray | None = None
) -> np.ndarray:
    """Model mode of each identified mode: the best MAC (when given), else the nearest
    frequency; each model mode used once."""
    score = -np.abs(np.log(f_ident[:, None] / np.maximum(f_model[None, :], 1e-12)))
    if mac_matrix is not None:
        score = mac_matrix + 1e-3 * score
    out: list[int] = []
    used: set[int] = set()
    for i in range(f_ident.size):
        order = np.argsort(-score[i])
        j = next(int(k) for k in order if int(k) not in used)
        used.add(j)
        out.append(j)
    return np.array(out, int)


def _calibrate_rig(
    cfg: CampaignConfig, rig: CameraRig, points0: np.ndarray, rng: np.random.Generator
) -> tuple[CalibrationResult, dict[str, Any]]:
    """Static calibration from averaged fields of the structure at rest (Att. 6 §1.6)."""
    true_cams = rig.cameras()
    n_fields = int(rig.static_fields)
    fields = simulate_centroids(
        true_cams,
        np.broadcast_to(points0, (n_fields,) + points0.shape),
        rig.pixel_size,
        rig.noise_px,
        rig.quantize,
        seed=int(rng.integers(2**31)),
    )
    if np.any(np.isnan(fields)):
        raise FieldError(
            "rig",
            "some targets fall outside a camera's 320 x 244 field; aim the "
            "cameras at the structure or use a shorter focal length",
        )
    obs = fields.mean(axis=1)
    sigma = rig.noise_px * rig.pixel_size / np.sqrt(n_fields)
    start = []
    for cam in true_cams:
        v = cam.vector()
        v[:3] += rng.normal(0.0, rig.position_error, 3)
        v[3:6] += rng.normal(0.0, rig.angle_error, 3)
        start.append(cam.with_vector(v))
    guess = points0 + rng.normal(0.0, cfg.target_sigma, points0.shape)
    res = calibrate(
        obs,
        start,
        guess,
        datum=None,
        scale=None,
        sigma=sigma,
        free=VIDEO_FREE,
        target_sigma=cfg.target_sigma,
    )
    idx = [CAMERA_PARAMETERS.index("fx" if p == "f" else p) for p in VIDEO_FREE]
    errors = []
    for j, (est, tru) in enumerate(zip(res.cameras, true_cams)):
        err = est.vector()[idx] - tru.vector()[idx]
        std = np.sqrt(np.diag(res.camera_covariance(j, VIDEO_FREE)))
        errors.append(err / std)
    z = np.concatenate(errors)
    return res, {
        "parameters": list(VIDEO_FREE),
        "n_cameras": len(true_cams),
        "normalised_errors": z.tolist(),
        "max_abs_normalised_error": float(np.abs(z).max()),
        "sigma0_squared": float(res.sigma0_squared),
        "image_sigma_px": float(rig.noise_px / np.sqrt(n_fields)),
    }


def _video_test(
    cfg: CampaignConfig,
    truth: ModalModel,
    rig: CameraRig,
    points0: np.ndarray,
    calibration: CalibrationResult,
    rng: np.random.Generator,
) -> tuple[Measurement, dict[str, Any]]:
    """Filmed free vibration: target z histories by triangulation with the calibrated cameras,
    relative to the calibrated rest positions of the targets."""
    cams, static_xyz = calibration.cameras, calibration.targets
    z_chan = [Channel.at("displacement", int(n), "z") for n in cfg.targets]
    test = simulate_test(
        truth,
        _blow(cfg.hammer_node, cfg.hammer_direction, cfg.video_impulse, cfg.field_rate),
        z_chan,
        cfg.video_duration,
        cfg.field_rate,
        seed=int(rng.integers(2**31)),
    )
    T = test.abscissa.size
    moving = np.broadcast_to(points0, (T,) + points0.shape).copy()
    moving[..., 2] += test.outputs.T
    uv = simulate_centroids(
        rig.cameras(),
        moving,
        rig.pixel_size,
        rig.noise_px,
        rig.quantize,
        seed=int(rng.integers(2**31)),
    )
    if np.any(np.isnan(uv)):
        raise FieldError(
            "rig",
            "a target leaves a camera's field during the video test; reduce "
            "video_impulse or widen the view",
        )
    pts, cov = triangulate(cams, uv, rig.noise_px * rig.pixel_size)
    # with the calibration covariance (Att. 6 Eqs. 34-37): the absolute position uncertainty;
    # the camera error is common to every field, so it largely cancels in the motion below
    _, cov_abs = triangulate(
        cams, uv[:, :1], rig.noise_px * rig.pixel_size, camera_covariance=calibration
    )
    z = (pts[..., 2] - static_xyz[None, :, 2]).T  # (targets, fields)
    err = z - test.outputs
    tri = {
        "predicted_sigma_z_m": float(np.sqrt(np.mean(cov[..., 2, 2]))),
        "predicted_sigma_z_with_cameras_m": float(np.sqrt(np.mean(cov_abs[..., 2, 2]))),
        "rms_error_z_m": float(np.sqrt(np.mean(err**2))),
        "peak_displacement_m": float(np.abs(test.outputs).max()),
        "fields": int(T),
    }
    video = Measurement(test.abscissa, z, tuple(z_chan), test.inputs, test.input_channels)
    return video, tri


def _node(channel: Channel) -> int:
    """The node of a measured channel (a Measurement's channels are located: Channel.at)."""
    assert channel.node is not None
    return channel.node


def _fe_vector(asm: Assembly, terms: Mapping[tuple[int, str], float]) -> np.ndarray:
    """Vector over the assembly's dofs with ``{(node, dof): weight}`` (clamped dofs dropped)."""
    v = np.zeros(asm.n_dofs)
    for (node, dof), weight in terms.items():
        try:
            v[asm.index(int(node), dof)] += weight
        except ValueError:
            continue  # a clamped end does not rotate
    return v


def _frf_points(
    estimate: FRFEstimate,
    cfg: CampaignConfig,
    asm: Assembly,
    gauges: Sequence[Channel],
    inputs: Sequence[Channel],
    resonances: np.ndarray,
    input_gains: bool = False,
) -> list[tuple[Any, ...]]:
    """Measured FRF points for the Att. 6 fit: the paper's grid (``frf_step`` Hz from 0.4 Hz
    to the band), away from every resonance, each with its H1 random error.

    With matched anti-aliasing filters on the torque and strain channels the H1 estimate is the
    continuous receptance.  Each point's SD is its H1 random error
    (:class:`~flexsat.identify.spectral.FRFEstimate`); the real part (Att. 6's ``h^r`` away
    from resonance) adds 0.5 % of ``|H|`` for the Welch bias, the imaginary part 10 % (it
    carries the damping, whose form the model only assumes).  Points where the output's
    coherence is below 0.9 are left out.
    """
    frf, coherence = estimate.frf, estimate.coherence
    f = frf.abscissa
    grid = np.arange(0.4, cfg.band + 1e-9, cfg.frf_step)
    idx = np.unique([int(np.argmin(np.abs(f - g))) for g in grid])
    w = 2 * np.pi * f[idx]
    clear = np.all(np.abs(w[:, None] / resonances[None, :] - 1) > RESONANCE_CLEARANCE, axis=1)
    points: list[tuple[Any, ...]] = []
    for i, g in enumerate(gauges):
        # located channels (Channel.at): a strain gauge has both its nodes and its axis
        assert g.node is not None and g.node_a is not None and g.direction is not None
        axis = "r" + g.direction
        c = _fe_vector(asm, {(g.node, axis): 1.0, (g.node_a, axis): -1.0})
        gam = np.clip(coherence[i, idx], 1e-6, 1.0)
        ok = clear & (gam > 0.9)
        for a, ch in enumerate(inputs):
            assert ch.node is not None and ch.direction is not None  # located: Channel.at
            b = _fe_vector(asm, {(ch.node, "r" + ch.direction): 1.0})
            H = frf.outputs[i, a, idx]
            random = estimate.std[i, a, idx]
            # real part: random error + 0.5 % Welch bias; imaginary part: + 10 % of |H|, since
            # away from resonance it carries the damping, which the Rayleigh form cannot follow
            sd = random + 0.005 * np.abs(H) + 1j * (random + 0.1 * np.abs(H))
            if np.any(ok):
                item = (c, b, w[ok], H[ok], sd[ok])
                # with unknown torque constants each wheel's column carries its gain nu[a]
                points.append(item + (None, a) if input_gains else item)
    return points


@dataclass(frozen=True)
class TestRecords:
    """What the tests recorded: the data an identification starts from, simulated by
    :func:`simulate_records` or read from test files (e.g. :meth:`Measurement.from_uff`).

    Attributes
    ----------
    hammer : Measurement
        Time histories of the hammer test with the blow's force as input.
    wheels : Measurement
        Time histories of the reaction-wheel test with the commanded torques as inputs (the
        output channels: the strain gauges whose FRFs the update fits).
    video : Measurement or None
        Target displacements normal to the structure (``z``) with the blow as input.
    calibration, triangulation : dict
        Summaries of the camera calibration and the triangulation (empty for recorded data).
    """

    hammer: Measurement
    wheels: Measurement
    video: Measurement | None = None
    calibration: dict[str, Any] = field(default_factory=dict)
    triangulation: dict[str, Any] = field(default_factory=dict)


def _true_modes(case: SubstructuredCase, cfg: CampaignConfig) -> tuple[Assembly, ModalModel]:
    """The truth: the case's finite-element model with ``truth_modes`` modes (default all)."""
    asm = case.structure().assemble()
    modes = asm.modes(asm.n_dofs if cfg.truth_modes is None else min(cfg.truth_modes, asm.n_dofs))
    return asm, _modal_model(
        asm, modes.omegas, modes.shapes, _truth_damping(cfg, modes.omegas.size)
    )


def simulate_records(
    case: SubstructuredCase, cfg: CampaignConfig, progress: Callable[[str], None] | None = None
) -> TestRecords:
    """Run the hammer, video and reaction-wheel tests on the true structure (module docstring).

    The truth is the case as built, with ``cfg.truth_damping``; the strain and accelerometer
    channels have anti-aliasing filters and noise; the hammer's force is recorded as the
    one-sample blow it is; the video test is calibrated and triangulated as in Att. 6.
    ``progress(label)``, if given, is called as each of :data:`SIMULATE_STEPS` starts.
    """
    say: Callable[[str], None] = progress or (lambda label: None)
    if cfg.rig is None or not cfg.targets or not cfg.strain_gauges or not cfg.wheel_nodes:
        raise FieldError(
            "rig",
            "simulating the tests needs a camera rig, targets, strain gauges and reaction wheels",
        )
    rng = np.random.default_rng(cfg.seed)
    asm, truth = _true_modes(case, cfg)
    gauges = [Channel.at("strain", int(b), ax, node_a=int(a)) for a, b, ax in cfg.strain_gauges]
    accels = [Channel.at("acceleration", int(n), d) for n, d in cfg.accelerometers]
    blow = _blow(cfg.hammer_node, cfg.hammer_direction, cfg.hammer_impulse, cfg.sample_rate)
    say(SIMULATE_STEPS[0])
    hammer = simulate_test(
        truth,
        blow,
        gauges + accels,
        cfg.hammer_duration,
        cfg.sample_rate,
        noise=cfg.noise,
        seed=int(rng.integers(2**31)),
        anti_alias=cfg.anti_alias * cfg.sample_rate,
    )
    # a hammer's force record is its one-sample blow (impulse / dt): the output filters then
    # belong to the identified system, and their poles lie above the band
    pulse = np.zeros((1, hammer.abscissa.size))
    pulse[0, 0] = cfg.hammer_impulse * cfg.sample_rate
    hammer = Measurement(
        hammer.abscissa,
        hammer.outputs,
        hammer.output_channels,
        pulse,
        hammer.input_channels,
        attrs=hammer.attrs,
    )

    coords = {int(n): xyz for n, xyz in zip(asm.node_ids, asm.coordinates)}
    points0 = np.array([coords[int(n)] for n in cfg.targets], float)
    say(SIMULATE_STEPS[1])
    calib, calib_summary = _calibrate_rig(cfg, cfg.rig, points0, rng)
    video, tri = _video_test(cfg, truth, cfg.rig, points0, calib, rng)

    wheels = [
        random_force(int(n), ax, cfg.wheel_torque_rms, load="torque")
        for n, ax in zip(cfg.wheel_nodes, cfg.wheel_axes)
    ]
    say(SIMULATE_STEPS[2])
    wheel_test = simulate_test(
        truth,
        wheels,
        gauges,
        cfg.wheel_duration,
        cfg.wheel_sample_rate,
        noise=cfg.noise,
        seed=int(rng.integers(2**31)),
        anti_alias=cfg.anti_alias * cfg.wheel_sample_rate,
    )
    gains = np.asarray(cfg.wheel_torque_constants, float)
    if gains.size:
        # the wheels deliver k x the commanded torque; the record holds the command (Att. 6
        # Att. 6 "Input and Strain Transformation Matrix": B carries each motor's current-to-torque
        # constant, not known a priori)
        wheel_test = Measurement(
            wheel_test.abscissa,
            wheel_test.outputs,
            wheel_test.output_channels,
            wheel_test.inputs / gains[:, None],
            wheel_test.input_channels,
            attrs=wheel_test.attrs,
        )
    return TestRecords(hammer, wheel_test, video, calib_summary, tri)


def run_campaign(
    case: SubstructuredCase, cfg: CampaignConfig, progress: Callable[[str], None] | None = None
) -> CampaignResult:
    """Test the true structure (:func:`simulate_records`), identify it and update the a-priori
    model (:func:`identify_and_update`), with the truth in the tables; ``progress`` as there."""
    return identify_and_update(
        case,
        cfg,
        simulate_records(case, cfg, progress),
        truth=_true_modes(case, cfg)[1],
        progress=progress,
    )


def _nearest(
    f_list: npt.ArrayLike, targets_hz: Iterable[float], tolerance: float = 0.05
) -> list[float | None]:
    """The value of ``f_list`` nearest each target (relative ``tolerance``), else None."""
    values = np.asarray(f_list)
    out: list[float | None] = []
    for f in targets_hz:
        k = int(np.argmin(np.abs(values - f))) if values.size else -1
        out.append(float(values[k]) if k >= 0 and abs(values[k] / f - 1) < tolerance else None)
    return out


def identify_and_update(
    case: SubstructuredCase,
    cfg: CampaignConfig,
    records: TestRecords,
    truth: ModalModel | None = None,
    progress: Callable[[str], None] | None = None,
) -> CampaignResult:
    """Identify the recorded tests and update the a-priori model (module docstring, 1-4).

    Parameters
    ----------
    case : object
        A case with ``structure(stiffness_scale=...)`` (a :class:`~flexsat.structures.fem.
        Structure` whose named substructure stiffnesses scale) and ``substructures`` (names),
        e.g. :func:`flexsat.cases.tamu_grid.tamu_grid`: the nominal model.  The a-priori model
        has ``cfg.a_priori_scale`` on its substructure stiffnesses; the scalings are reported
        as factors on the nominal model.
    cfg : CampaignConfig
        The identification settings (``band``, ``era_order``, ``bootstrap_samples``,
        ``update``, ``frf_segment``, ``frf_step``, ``a_priori_*``); the torque constants are
        identified when ``wheel_torque_constants`` is given (their values, known only in a
        simulation, fill the ``true`` column).
    records : TestRecords
        Channels, nodes and sample rates come from the records.
    truth : ModalModel, optional
        The true structure of a simulation, for the ``true_*`` columns (None: measured data).
    progress : callable, optional
        ``progress(label)`` is called as each of :data:`IDENTIFY_STEPS` starts.

    Returns
    -------
    CampaignResult
    """
    say: Callable[[str], None] = progress or (lambda label: None)
    rng = np.random.default_rng([cfg.seed, 1])
    names = tuple(case.substructures)

    # --- a-priori model and its substructure blocks (Att. 6 Eq. 5) -----------------------------
    base = {n: float(cfg.a_priori_scale.get(n, 1.0)) for n in names}

    def build(kf: np.ndarray, _mf: np.ndarray | None) -> Assembly:
        return case.structure(
            stiffness_scale={n: base[n] * k for n, k in zip(names, kf)}
        ).assemble()

    sub = substructures_from_builder(build, len(names), n_mass=0, names=names)
    apriori_asm = build(np.ones(len(names)), None)
    M = sub.M()
    sub = SubstructureModel(sub.K_blocks, [], [M, sub.K()], sub.K0, M, names=names)
    w0, phi0 = sub.modes()
    zeta0 = cfg.a_priori_damping * w0[0] / w0  # Att. 6 Eq. 15: C = 2 z1 w1 M

    # --- 1. hammer test: ERA on RMS-normalised channels (units differ; eigenvalues unchanged) --
    say(IDENTIFY_STEPS[0])
    hammer = records.hammer
    scale = np.sqrt(np.mean(hammer.outputs**2, axis=1))
    Y = markov_parameters(hammer) / scale[None, :, None]
    hammer_real = era(Y, hammer.dt, order=cfg.era_order)
    if cfg.bootstrap_samples:
        hammer_real = bootstrap_uncertainty(
            hammer_real, Y, cfg.bootstrap_samples, seed=int(rng.integers(2**31))
        )
    sel = _select(hammer_real, cfg.band)
    if sel.size == 0:
        raise FieldError("records", f"the hammer test shows no mode below {cfg.band:g} Hz")
    f_meas = hammer_real.frequencies_hz[sel]
    omega_meas = hammer_real.omega_rad_s[sel]
    z_meas = hammer_real.damping[sel]
    # era() always gives the perturbation uncertainty; the bootstrap replaces it
    assert hammer_real.frequency_std_hz is not None and hammer_real.damping_std is not None
    f_std = hammer_real.frequency_std_hz[sel]
    z_std = hammer_real.damping_std[sel]

    # --- 2. video test: ERA shapes at the targets ----------------------------------------------
    say(IDENTIFY_STEPS[1])
    video_shapes, video_f, video_index, rows = np.zeros((0, 0)), np.zeros(0), np.zeros(0, int), []
    video_real = None
    if records.video is not None:
        video = records.video
        video_real = era(markov_parameters(video), video.dt, order=cfg.era_order)
        vsel = _select(video_real, cfg.band, min_mpc=0.3)
        video_shapes = _real_shapes(video_real.shapes[:, vsel])
        video_f = video_real.frequencies_hz[vsel]
        rows = [apriori_asm.index(_node(c), f"u{c.direction}") for c in video.output_channels]

    # --- pair modes: video shapes against the a-priori model, then hammer by frequency ---------
    hammer_index = _pair(f_meas, w0 / (2 * np.pi))
    if video_f.size:
        video_index = _pair(video_f, w0 / (2 * np.pi), mac(video_shapes, phi0[rows]))
        for i, fv in zip(video_index, video_f):
            # where a video mode and a hammer mode agree in frequency, the MAC pairing wins
            k = np.flatnonzero(np.abs(f_meas / fv - 1) < 0.02)
            if k.size:
                hammer_index[k[0]] = i
        if len(set(hammer_index.tolist())) != hammer_index.size:
            hammer_index = _pair(f_meas, w0 / (2 * np.pi))

    # --- 3. reaction-wheel test: H1 FRFs and OKID -----------------------------------------------
    say(IDENTIFY_STEPS[2])
    wheel_test = records.wheels
    gauges, inputs = list(wheel_test.output_channels), list(wheel_test.input_channels)
    estimate = estimate_frf(wheel_test, cfg.frf_segment)
    frf, coh = estimate.frf, estimate.coherence
    assert wheel_test.inputs is not None  # estimate_frf refuses a test without inputs
    gscale = np.sqrt(np.mean(wheel_test.outputs**2, axis=1))
    n_obs = int(np.ceil(cfg.era_order / len(gauges))) + 4
    Y_okid = okid(wheel_test.inputs, wheel_test.outputs / gscale[:, None], 4 * n_obs, n_obs)
    okid_real = era(Y_okid, wheel_test.dt, order=cfg.era_order)
    osel = _select(okid_real, cfg.band)

    # --- 4. update ------------------------------------------------------------------------------
    say(IDENTIFY_STEPS[3])
    true_gains = np.asarray(cfg.wheel_torque_constants, float)
    fit_gains = bool(true_gains.size) or cfg.identify_torque_constants
    if true_gains.size and true_gains.size != len(inputs):
        raise FieldError(
            "wheel_torque_constants",
            f"one per recorded wheel ({len(inputs)}), got {true_gains.size}",
        )
    wheel_gains, nu1 = {}, np.ones(len(inputs))
    r0 = np.array([2.0 * cfg.a_priori_damping * w0[0], 0.0])  # Eq. 15 in C = r1 M + r2 K
    if cfg.update == "creamer_junkins":
        # stiffness from the frequencies (Att. 7 Eq. 9b), then damping (Eq. 24)
        und = identify_undamped(
            sub,
            omega_meas,
            mode_indices=hammer_index,
            frequency_sigma=2 * np.pi * np.maximum(f_std, 1e-9 * f_meas),
        )
        lam = 2 * np.pi * f_meas * (-z_meas + 1j * np.sqrt(1 - z_meas**2))
        p1, r1 = und.p, identify_damping(sub, lam, und.p, None, mode_indices=hammer_index).r
        p_cov = und.covariance[: len(names), : len(names)]
        update = {
            "method": cfg.update,
            "frf_points": 0,
            "iterations": int(und.iterations),
            "converged": bool(und.converged),
        }
    else:
        # free and forced response together (Att. 6 Eqs. 3-13)
        points = _frf_points(
            estimate,
            cfg,
            apriori_asm,
            gauges,
            inputs,
            np.concatenate([w0, omega_meas]),
            fit_gains,
        )
        data = CorrectionData(
            frequencies=omega_meas,
            frequency_modes=hammer_index,
            frequency_sigma=2 * np.pi * np.maximum(f_std, 1e-9 * f_meas),
            damping_ratios=z_meas,
            damping_sigma=np.hypot(z_std, DAMPING_FORM_ERROR * z_meas),
            damping_modes=hammer_index,
            frf=points,
        )
        dc = differential_correction(sub, data, r0=r0)
        p1, r1 = dc.p, dc.r
        p_cov = dc.covariance[: len(names), : len(names)]
        if fit_gains:
            nu_std = np.sqrt(np.clip(np.diag(dc.covariance)[-len(inputs) :], 0.0, None))
            truth_k = true_gains if true_gains.size else [None] * len(inputs)
            wheel_gains = {
                c.name: {
                    "true": None if k is None else float(k),
                    "identified": float(v),
                    "std": float(sd),
                }
                for c, k, v, sd in zip(inputs, truth_k, dc.nu, nu_std)
            }
            nu1 = dc.nu
        update = {
            "method": cfg.update,
            "frf_points": int(sum(len(pt[2]) for pt in points)),
            "iterations": int(dc.iterations),
            "converged": bool(dc.converged),
        }
    w1, phi1 = sub.modes(p1)
    C1 = sub.C(r1)
    zeta1 = np.clip(np.einsum("ij,ik,kj->j", phi1, C1, phi1) / (2 * w1), 1e-6, None)

    # the anti-aliasing filters cancel in H1: the measurement is the continuous FRF
    keep = frf.abscissa <= cfg.band
    freqs = frf.abscissa[keep]
    frf_a = frequency_response(_modal_model(apriori_asm, w0, phi0, zeta0), gauges, inputs, freqs)
    frf_u = frequency_response(_modal_model(apriori_asm, w1, phi1, zeta1), gauges, inputs, freqs)
    frf_u = frf_u * nu1[None, :, None]  # relative to the commanded torque

    # --- tables ----------------------------------------------------------------------------------
    if truth is not None:
        f_true = truth.frequencies / (2 * np.pi)
        idx = np.array([int(np.argmin(np.abs(f_true - f))) for f in f_meas], int)
        true_hz, true_z = f_true[idx].tolist(), truth.damping[idx].tolist()
    else:
        true_hz = true_z = [None] * f_meas.size
    modes_table = {
        "model_index": hammer_index.tolist(),
        "true_hz": true_hz,
        "true_damping": true_z,
        "era_hz": f_meas.tolist(),
        "era_hz_std": f_std.tolist(),
        "era_damping": z_meas.tolist(),
        "era_damping_std": z_std.tolist(),
        "video_hz": _nearest(video_f, f_meas),
        "okid_hz": _nearest(okid_real.frequencies_hz[osel], f_meas),
        "a_priori_hz": (w0[hammer_index] / (2 * np.pi)).tolist(),
        "a_priori_damping": zeta0[hammer_index].tolist(),
        "updated_hz": (w1[hammer_index] / (2 * np.pi)).tolist(),
        "updated_damping": zeta1[hammer_index].tolist(),
    }
    std = np.sqrt(np.clip(np.diag(p_cov), 0.0, None))
    scalings = {
        n: {"a_priori": base[n], "p": float(p), "p_std": float(s), "updated": float(base[n] * p)}
        for n, p, s in zip(names, p1, std)
    }
    mac_updated = mac_apriori = np.zeros((0, 0))
    if video_f.size:
        n_cols = int(video_index.max()) + 3
        mac_updated = mac(video_shapes, phi1[rows][:, :n_cols])
        mac_apriori = mac(video_shapes, phi0[rows][:, :n_cols])
    targets = tuple(_node(c) for c in records.video.output_channels) if records.video else ()
    return CampaignResult(
        names,
        modes_table,
        scalings,
        wheel_gains,
        update,
        r1,
        mac_apriori,
        mac_updated,
        freqs,
        frf.outputs[:, :, keep],
        coh[:, keep],
        frf_a,
        frf_u,
        tuple(c.name for c in gauges),
        tuple(c.name for c in inputs),
        video_shapes,
        targets,
        records.calibration,
        records.triangulation,
        hammer_real,
        video_real,
        okid_real,
    )
