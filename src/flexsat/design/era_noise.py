"""Accuracy of the Eigensystem Realization Algorithm against measurement noise: synthetic tests
(:func:`flexsat.sim.vibration_test.simulate_test`) at several noise levels and seeds, identified
by ERA (J.-N. Juang and R. S. Pappa, "An eigensystem realization algorithm for modal parameter
identification and model reduction", J. Guidance 8(5), 1985, 620-627)."""

from __future__ import annotations

import numpy as np

from flexsat.identify.era import era
from flexsat.identify.markov import markov_parameters
from flexsat.sim.vibration_test import simulate_test

__all__ = ["noise_damping_sweep"]


def noise_damping_sweep(
    modal_model, noise_levels, sensors, excitation, duration, sample_rate, seeds=(0,), **era_kwargs
):
    """Relative frequency and damping errors of ERA versus measurement noise.

    Runs :func:`~flexsat.sim.vibration_test.simulate_test` with each noise level and seed,
    :func:`~flexsat.identify.markov.markov_parameters` and :func:`~flexsat.identify.era.era` with
    ``order = 2 m``, matches each true mode to
    the nearest identified frequency and returns a dict with ``noise`` (k,),
    ``frequency_error`` and ``damping_error`` (k, m): mean over seeds of the absolute relative
    errors.
    """
    f_true = modal_model.frequencies_hz
    z_true = modal_model.damping
    fe, ze = [], []
    for level in noise_levels:
        f_err, z_err = [], []
        for seed in seeds:
            meas = simulate_test(
                modal_model, excitation, sensors, duration, sample_rate, noise=level, seed=seed
            )
            Y = markov_parameters(meas)
            kw = dict(order=2 * modal_model.n_modes) | era_kwargs
            res = era(Y, dt=meas.dt, **kw)
            idx = np.argmin(np.abs(res.frequencies_hz[None, :] - f_true[:, None]), axis=1)
            f_err.append(np.abs(res.frequencies_hz[idx] / f_true - 1))
            z_err.append(np.abs(res.damping[idx] / z_true - 1))
        fe.append(np.mean(f_err, axis=0))
        ze.append(np.mean(z_err, axis=0))
    return {
        "noise": np.asarray(noise_levels, float),
        "frequency_error": np.array(fe),
        "damping_error": np.array(ze),
    }
