"""The hybrid-coordinate plant built from a cantilevered ModalModel (seed 001 Eq. 16)."""

import numpy as np
import pytest

from flexsat.cases import nps, tamu
from flexsat.control import PD
from flexsat.dynamics.hybrid import ModalHybrid
from flexsat.sim import Impulses, SimConfig, simulate
from flexsat.structures.modal_model import ModalModel

EPS = np.finfo(float).eps


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
    plant = ModalHybrid(
        case.modal_model(), case.hub_inertia_value, axis="z", tip=(case.reflector_node, "y")
    )
    cfg = SimConfig(duration=20.0, control_rate=10.0, impulses=Impulses((0.0,), (0.5,)))
    r = simulate(plant, PD(0.0, 0.0), cfg, record_states=True)
    x = r.dataset.state.values[0]
    h = x[:, plant.ndof :] @ plant.mass_matrix[0]
    assert np.allclose(h[1:], 0.5, rtol=1e-10)
    assert np.abs(r.dataset.tip_deflection.values[0]).max() > 0


def test_the_hub_inertia_takes_units_and_refuses_a_wrong_dimension():
    modal = ModalModel.from_hub_appendage(tamu(n_modes=2).model())
    si = ModalHybrid(modal, 0.353, axis="z")
    with_units = ModalHybrid(modal, "3530 kg*cm**2", axis="z")  # 0.353 kg m², converted by pint
    assert with_units.hub_inertia == pytest.approx(si.hub_inertia, rel=1e-15)
    np.testing.assert_array_equal(with_units.mass_matrix[1:, 1:], si.mass_matrix[1:, 1:])
    with pytest.raises(ValueError, match="^hub_inertia"):
        ModalHybrid(modal, "0.353 kg*m", axis="z")


def test_free_modal_model_is_refused():
    from flexsat.cases import free_free_beam

    beam = free_free_beam(n_elements=4)
    asm = beam.structure().assemble()
    modal = ModalModel.from_fe(asm.modes(8, rigid_body_modes=6))
    with pytest.raises(ValueError, match=r"^modal: hybrid coordinates need a cantilevered"):
        ModalHybrid(modal, 1.0)


@pytest.mark.parametrize(
    "plant",
    [
        nps().model(),
        tamu(n_modes=4).model(),
        ModalHybrid(ModalModel.from_hub_appendage(tamu(n_modes=4).model()), 0.353, axis="z"),
    ],
    ids=["nps", "tamu", "modal_hybrid"],
)
def test_energy_and_momentum_are_the_plants_quadratic_and_linear_forms(plant):
    """E = ½ xᵀ Q x with Q = blockdiag(K, M) (Att. 3 Eq. 7) and h = r · x (the compiled loop
    records these per sample), and the vibration energy E − (r · x)² / (2 I_tot); to 16 eps of
    the energy scale ½ |x|² ‖Q‖ (two orders of summation of n_x products)."""
    x = np.random.default_rng(6).standard_normal((5, plant.nx))
    Q = plant.energy_matrix
    assert np.array_equal(Q, Q.T)
    scale = 0.5 * np.abs(Q).max() * (x**2).sum(axis=-1) * plant.nx
    E = plant.energy(x)
    assert np.all(np.abs(0.5 * np.einsum("ci,ij,cj->c", x, Q, x) - E) <= 16 * EPS * scale)
    h = x @ plant.momentum_row
    np.testing.assert_allclose(h, plant.momentum(x), rtol=16 * EPS)
    vib = E - 0.5 * h**2 / plant.total_inertia
    assert np.all(np.abs(vib - plant.vibration_energy(x)) <= 16 * EPS * scale)


def test_a_stiffened_plant_has_no_quadratic_energy():
    """With the stiffening term the energy is quartic (Att. 3 Eq. 7): no energy matrix, so the
    compiled loop keeps the states for it."""
    assert tamu(n_modes=4, stiffening=True).model().energy_matrix is None


@pytest.mark.parametrize("field", ["outputs", "nonlinear", "energy_matrix"])
def test_the_derived_plant_fields_are_read_only(field):
    """A hybrid plant's outputs (its output_channels), nonlinearity (its stiffening) and energy
    matrix (blockdiag(K, M)) follow from the model: assigning one is an AttributeError naming
    the field, not a silently inconsistent plant."""
    plant = ModalHybrid(ModalModel.from_hub_appendage(tamu(n_modes=2).model()), 0.353, axis="z")
    with pytest.raises(AttributeError, match=rf"^{field}: ModalHybrid"):
        setattr(plant, field, getattr(plant, field))
