"""The hybrid-coordinate plant built from a cantilevered ModalModel (seed 001 Eq. 16)."""

import numpy as np
import pytest

from flexsat.cases import nps, tamu
from flexsat.control import PD
from flexsat.dynamics.hybrid import ModalHybrid
from flexsat.sim import Impulses, SimConfig, simulate
from flexsat.structures.modal_model import ModalModel


@pytest.fixture(scope="module")
def case():
    return nps()


def test_matrices_are_the_nps_hybrid_model(case):
    plant = case.model()
    M, C, K = case.hybrid_matrices()
    assert np.array_equal(plant.mass_matrix, M)
    assert np.array_equal(plant.damping_matrix, C)
    assert np.array_equal(plant.stiffness_matrix, K)
    assert plant.hub_inertia == pytest.approx(case.hub_inertia_value)
    assert plant.appendage_inertia == pytest.approx(plant.total_inertia - plant.hub_inertia)


def test_hub_equation_defines_the_reaction_torque(case):
    """I_hub θ'' = u − root_torque (one appendage), for any state and torque."""
    plant = case.model()
    rng = np.random.default_rng(4)
    x = 1e-2 * rng.standard_normal((4, plant.nx))
    u = rng.standard_normal(4)
    y = plant.outputs(x, u)
    thdd = plant.acceleration(x, u)[:, 0]
    assert np.allclose(plant.hub_inertia * thdd, u - y["root_torque"], rtol=1e-12, atol=1e-14)


def test_hub_appendage_through_a_modal_model_gives_the_same_plant():
    """TAMU hub + appendages → ModalModel → ModalHybrid: the same free-vehicle frequencies."""
    model = tamu(n_modes=4).model()
    modal = ModalModel.from_hub_appendage(model)
    plant = ModalHybrid(modal, model.params.hub_inertia, axis="z")
    assert np.allclose(plant.hub_free_frequencies(), model.frequencies(), rtol=1e-10)
    assert plant.total_inertia == pytest.approx(model.params.total_inertia, rel=1e-12)


def test_engine_runs_the_modal_plant_and_conserves_momentum(case):
    plant = ModalHybrid(case.modal_model(), case.hub_inertia_value, axis="z",
                        tip=(case.reflector_node, "y"))
    cfg = SimConfig(duration=20.0, control_rate=10.0, impulses=Impulses((0.0,), (0.5,)))
    r = simulate(plant, PD(0.0, 0.0), cfg, record_states=True)
    x = r.dataset.state.values[0]
    h = x[:, plant.ndof:] @ plant.mass_matrix[0]
    assert np.allclose(h[1:], 0.5, rtol=1e-10)
    assert np.abs(r.dataset.tip_deflection.values[0]).max() > 0


def test_free_modal_model_is_refused():
    from flexsat.cases import free_free_beam

    beam = free_free_beam(n_elements=4)
    asm = beam.structure().assemble()
    modal = ModalModel.from_fe(asm.modes(8, rigid_body_modes=6))
    with pytest.raises(ValueError, match=r"^modal: hybrid coordinates need a cantilevered"):
        ModalHybrid(modal, 1.0)
