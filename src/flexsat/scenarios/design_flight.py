r"""Flying a design study's nominal laws on dispersed truths, many cases at once: the flight
of the dispersions stage (:mod:`flexsat.scenarios.design_dispersions`).

A case is a :class:`CaseSetup`: its truth spacecraft, its run settings (sensors, disturbances,
simulation) and each flown run's initial state. :func:`fly_cases` flies consecutive cases
whose settings and initial states agree in one batch: their truths stacked into a
:class:`~flexsat.dynamics.dispersion.DispersedPlant` (:func:`~flexsat.dynamics.dispersion.
stack_plants`), one :func:`~flexsat.sim.engine.simulate` call per run, which takes the
compiled three-axis kernel (:mod:`flexsat.sim.compiled_attitude`) with every case in its own
lane: the PD, LQR and PPF laws and the scheduled perturbation feedback (through its linear
form, :meth:`~flexsat.control.PerturbationFeedback.linear_form`) run compiled, each case's
noise from its own seed. A case's numbers depend on its own plant, seed and initial state only
(the kernel's lanes do not mix, the recorded outputs are one product per case), so a case
flown alone equals the same case in any batch, bit for bit.

The nominal spacecraft of a study (the kept modes with the placed forces: 0.3 s to build for
the EPS from its solved modal model) is built once per process and stage fingerprint
(:func:`nominal_setup`); a *direct* case (every dispersed parameter under ``truth``) is that
spacecraft with its own departures (:func:`~flexsat.scenarios.slew.apply_truth`: principal
moments, elastic frequencies, damping), made in well under a millisecond, without a case
document.

:func:`fly` flies one case's document alone through the engine as a run of the study would:
the reference the batched path is tested against.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.scenarios.errors import ScenarioError, locate

if TYPE_CHECKING:
    from flexsat.control.base import Controller
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.scenarios.design_dispersions import DispersedCases
    from flexsat.scenarios.design_placement import PlacementResult
    from flexsat.sim import SimConfig
    from flexsat.structures.modal_model import ModalModel


def dispersed_spacecraft(
    scenario: Any,
    placement: PlacementResult,
    model: ModalModel | None = None,
    reference: ModalModel | None = None,
) -> FlexibleSpacecraft:
    """The truth of a (case) design study: its ``model:`` solved (or ``model``, the nominal
    solve, when no dispersion touches the model section), its ``modes:`` kept, their signs
    those of the ``reference`` (the nominal kept modes, :func:`align_modes`) when given, with
    the nominal ``placement``'s forces and sensors.

    Raises
    ------
    ScenarioError
        A model or modes the solve refuses (a negative modulus, too few modes), by path.
    """
    from flexsat.scenarios.design_placement import spacecraft
    from flexsat.scenarios.design_study import kept_modes, modal_model_of

    try:
        if model is None:
            model = modal_model_of(scenario.model, scenario.folder)
    except ValueError as exc:
        raise ScenarioError([locate("model", exc)]) from None
    try:
        kept = kept_modes(model, scenario.modes)
    except ValueError as exc:
        raise ScenarioError([locate("modes", exc)]) from None
    if reference is not None:
        kept = align_modes(kept, reference)
    try:
        return spacecraft(kept, scenario.placement, placement)
    except ValueError as exc:
        raise ScenarioError([locate("placement", exc)]) from None


def align_modes(modes: ModalModel, reference: ModalModel) -> ModalModel:
    r"""``modes`` with each elastic mode's sign that of the ``reference`` mode at its index:
    :math:`\phi_i \leftarrow -\phi_i` (and its participation) where
    :math:`\phi_{ref,i}^T \phi_i < 0`, over every node and component.

    An eigen-solver returns each mode up to its sign, and two solves of nearby structures
    (a dispersed modulus or mass) need not pick the same one (measured on
    ``examples/own_spacecraft_design_study.yaml``: tip masses 0.9 and 1.1 kg flip the 32 Hz
    pair). A law designed on the nominal modes that reads modal coordinates (LQR, the
    perturbation feedback) would then feed the flipped mode back with the opposite sign; with
    the signs aligned it meets the same physical motion it was designed for. The sign changes
    no physics (the coordinate η_i and the shape flip together: every physical output is the
    same). The order is kept (frequencies ascending): a dispersion that makes two modes cross
    still swaps them under the law. Returned unchanged when the elastic mode counts or the node
    sets differ.
    """
    from flexsat.structures.modal_model import RIGID_FREQUENCY

    elastic = np.flatnonzero(modes.frequencies > RIGID_FREQUENCY)
    ref = np.flatnonzero(reference.frequencies > RIGID_FREQUENCY)
    if elastic.size != ref.size or modes.shapes.shape[1:] != reference.shapes.shape[1:]:
        return modes
    dots = np.einsum("ijk,ijk->i", modes.shapes[elastic], reference.shapes[ref])
    sign = np.ones(modes.n_modes)
    sign[elastic[dots < 0]] = -1.0
    if np.all(sign > 0):
        return modes
    return replace(
        modes,
        shapes=modes.shapes * sign[:, None, None],
        participation=modes.participation * sign[:, None],
    )


@dataclass(frozen=True)
class CaseSetup:
    """One case ready to fly: its ``plant`` (the truth), the ``config`` of its runs, each
    flown run's initial state (by label) and the key of the batch it may join (cases whose
    settings and initial states agree fly in one compiled batch, each in its own lane)."""

    plant: FlexibleSpacecraft
    config: SimConfig
    initial: dict[str, np.ndarray]
    group: str


@dataclass(frozen=True)
class Nominal:
    """What every direct case of a worker shares (:func:`nominal_setup`): the nominal study,
    its spacecraft (the kept modes with the placed forces, before the truth), the runs'
    settings and initial states."""

    scenario: Any
    plant: FlexibleSpacecraft
    config: SimConfig
    initial: dict[str, np.ndarray]


#: nominal setups kept per process, by the dispersions stage's fingerprint (a worker flies one
#: study's cases; a few more serve tests that run several studies in one process)
NOMINALS_KEPT = 4
_nominals: OrderedDict[str, Nominal] = OrderedDict()
_nominals_lock = threading.Lock()


def nominal_setup(build: DispersedCases) -> Nominal:
    """The :class:`Nominal` of ``build``'s study, made once per process and stage fingerprint:
    the nominal document validated and its spacecraft built (0.3 s for the EPS's, against a
    few milliseconds for the rest of a direct case)."""
    with _nominals_lock:
        found = _nominals.get(build.key)
        if found is not None:
            _nominals.move_to_end(build.key)
            return found
    from flexsat.scenarios.design_study import flight_config, flown_plant
    from flexsat.scenarios.fields import given_fields

    scenario: Any = replace(build.cases, parameters=()).scenario({}, 0)
    plant = dispersed_spacecraft(scenario, build.placement, build.model, build.reference)
    config = flight_config(scenario, flown_plant(scenario, plant))
    initial = {
        run.label: plant.state_from(**given_fields(run.initial))
        for run in scenario.runs
        if run.label in build.runs
    }
    made = Nominal(scenario, plant, config, initial)
    with _nominals_lock:
        _nominals[build.key] = made
        while len(_nominals) > NOMINALS_KEPT:
            _nominals.popitem(last=False)
    return made


def fly_cases(
    build: DispersedCases,
    setups: list[CaseSetup],
    seeds: np.ndarray,
    controllers: Mapping[str, Controller],
) -> dict[str, np.ndarray]:
    """The metrics (module docstring) of the cases ``setups`` with noise ``seeds``: each run of
    ``build.runs`` flown by its nominal law (``controllers``, by run label) on every case's
    truth, consecutive cases of one group in one batch of a
    :class:`~flexsat.dynamics.dispersion.DispersedPlant` (each case in its own lane of the
    three-axis kernel: its numbers do not depend on its batch).

    A perturbation law's linear form is that of the law while the error quaternion keeps its
    sign (:meth:`~flexsat.control.PerturbationFeedback.linear_form`); a case whose attitude
    leaves that hemisphere is flown again alone on the law itself (the Python loop).

    Raises
    ------
    SimulationDiverged
        Naming the cases by their place in ``setups``.
    """
    from flexsat.control import PerturbationFeedback
    from flexsat.dynamics.dispersion import stack_plants
    from flexsat.scenarios.design_study import IDENTITY, batch_metrics
    from flexsat.sim import SimulationDiverged, simulate
    from flexsat.sim.engine import offset_cases

    groups: list[tuple[int, int]] = []
    for k, setup in enumerate(setups):
        if groups and setups[groups[-1][0]].group == setup.group:
            groups[-1] = (groups[-1][0], k + 1)
        else:
            groups.append((k, k + 1))
    out: dict[str, list[np.ndarray]] = {}
    for label in build.runs:
        controller = controllers[label]
        target = np.asarray(build.laws[build.law_of[label]].get("beta_target", IDENTITY))
        rows: dict[str, np.ndarray] = {}
        for g0, g1 in groups:
            cases = setups[g0:g1]
            # a lone case flies beside a copy of itself: the kernel's shared-plant branch (one
            # plant for every lane) orders its sums otherwise than the per-case one, which a
            # batch of two or more takes (measured: 1e-11 relative apart on the flagship)
            lanes = cases if len(cases) > 1 else cases * 2
            x0 = np.stack([c.initial[label] for c in lanes])
            try:
                result = simulate(
                    stack_plants([c.plant for c in lanes]),
                    controller,
                    cases[0].config,
                    n_cases=len(lanes),
                    seeds=np.resize(seeds[g0:g1], len(lanes)),
                    initial_state=x0,
                    batch_independent=True,
                )
            except SimulationDiverged as exc:
                if len(cases) == 1 and exc.cases == (0, 1):  # the case and its copy
                    message = str(exc).replace("in case(s) 0, 1:", "in case(s) 0:", 1)
                    exc = SimulationDiverged(message, (0,), exc.time, exc.cause)
                raise offset_cases(exc, g0) from None
            metrics = {k: v[: g1 - g0] for k, v in batch_metrics(result, target).items()}
            if isinstance(controller, PerturbationFeedback):
                times = result.dataset["time"].values
                attitude = result.dataset["attitude"].transpose("case", "time", ...).values
                folded = np.flatnonzero((controller.hemisphere(times, attitude) < 0).any(axis=1))
                for i in folded:  # the law itself, in the Python loop
                    alone = simulate(
                        cases[i].plant,
                        controller,
                        cases[i].config,
                        n_cases=1,
                        seeds=seeds[g0 + i : g0 + i + 1],
                        initial_state=x0[i : i + 1],
                        compiled=False,
                    )
                    for name, value in batch_metrics(alone, target).items():
                        metrics[name][i] = value[0]
            for name, values in metrics.items():
                rows.setdefault(name, np.empty(len(setups)))[g0:g1] = values
        for name, values in rows.items():
            key = name if len(build.runs) == 1 else f"runs[{label!r}].{name}"
            out[key] = [values]
    return {name: parts[0] for name, parts in out.items()}


def fly(
    scenario: Any,
    runs: list[str],
    placement: PlacementResult,
    laws: Mapping[str, Any],
    model: ModalModel | None = None,
) -> dict[str, float]:
    """The metrics of the named ``runs`` of a (case) design study flown on its truth
    (:func:`dispersed_spacecraft` with the ``truth`` section's departures) with the nominal
    law designs (module docstring), in the Python loop of the engine or the compiled one as
    the engine chooses, each run alone: the reference the batched cases are tested against.

    Parameters
    ----------
    scenario : DesignStudyScenario
        The case's study: its model, modes, truth, sensors, simulation and runs' initial
        states are the truth.
    runs : list of str
        The labels of the runs flown.
    placement : PlacementResult
        The nominal placement.
    laws : mapping of str to dict of str to ndarray
        The nominal designs' arrays by law label.
    model : ModalModel, optional
        The nominal solve, when the case's model section is the nominal one.

    Raises
    ------
    ScenarioError
        A truth the model, modes or runs refuse, by path.
    """
    from flexsat.scenarios.design_laws import law_controller
    from flexsat.scenarios.design_study import IDENTITY, flight_config, flown_plant, run_metrics
    from flexsat.scenarios.errors import item_path
    from flexsat.scenarios.fields import given_fields
    from flexsat.sim import simulate

    nominal = dispersed_spacecraft(scenario, placement, model)
    plant = flown_plant(scenario, nominal)
    config = flight_config(scenario, plant)
    specs = {law.label: law for law in scenario.laws}
    records = []
    for index, run in enumerate(scenario.runs):
        if run.label not in runs:
            continue
        try:
            x0 = plant.state_from(**given_fields(run.initial))
        except ValueError as exc:
            path = f"runs{item_path(index, run.label)}.initial"
            raise ScenarioError([locate(path, exc)]) from None
        arrays = laws[run.law]
        controller = law_controller(specs[run.law], arrays, nominal, config.dt)
        result = simulate(plant, controller, config, n_cases=1, initial_state=x0)
        target = np.asarray(arrays.get("beta_target", IDENTITY))
        records.append((run.label, run_metrics(result, target)))
    if len(records) == 1:
        return records[0][1]
    return {f"runs[{label!r}].{k}": v for label, metrics in records for k, v in metrics.items()}


def inertia_margins(plant: FlexibleSpacecraft, scales: np.ndarray) -> list[int]:
    """The cases (rows of ``scales``, (n, 3) principal-moment factors) nearest to breaking
    the inertia's rules when the nominal ``plant``'s principal moments λ are scaled
    (:func:`~flexsat.scenarios.slew.apply_truth`): the least triangle margin
    min_i(s_j λ_j + s_k λ_k − s_i λ_i) and the least eigenvalue of J' − ΔᵀΔ; building their
    truths decides the rules for every case (each margin is the one the rule tests)."""
    moments, axes = np.linalg.eigh(plant.inertia)
    scaled = scales * moments
    triangle = scaled.sum(axis=1, keepdims=True) - 2 * scaled
    J = np.einsum("ij,cj,kj->cik", axes, scaled, axes)
    coupling = plant.coupling.T @ plant.coupling
    smallest = np.linalg.eigvalsh(J - coupling).min(axis=1)
    return [int(np.argmin(triangle.min(axis=1))), int(np.argmin(smallest))]


__all__ = [
    "NOMINALS_KEPT",
    "CaseSetup",
    "Nominal",
    "align_modes",
    "dispersed_spacecraft",
    "fly",
    "fly_cases",
    "inertia_margins",
    "nominal_setup",
]
