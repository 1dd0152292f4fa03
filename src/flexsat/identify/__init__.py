"""System identification from vibration tests: test data, synthetic tests, realization (ERA,
OKID), and Creamer-Junkins structural identification and model update."""

from flexsat.identify.era import (
    Realization,
    era,
    era_dc,
    mac,
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
from flexsat.identify.structural import (
    SubstructureModel,
    identify_damping,
    identify_undamped,
    modal_energy_distribution,
    substructures_from_builder,
    update_model,
)

__all__ = [
    "CHANNEL_KINDS",
    "Channel",
    "Excitation",
    "Measurement",
    "Realization",
    "SubstructureModel",
    "era",
    "era_dc",
    "harmonic_shaker",
    "identify_damping",
    "identify_undamped",
    "impulse_hammer",
    "mac",
    "markov_parameters",
    "modal_energy_distribution",
    "noise_damping_sweep",
    "okid",
    "random_force",
    "simulate_test",
    "substructures_from_builder",
    "torque_history",
    "update_model",
]
