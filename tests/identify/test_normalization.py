"""Modal normalisation from FRFs (:mod:`flexsat.identify.structural.normalization`, Att. 7
Eqs. 5-6) on the portal frame of tests/identify/conftest.py."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify.structural import (
    fit_modal_normalization,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


def test_fit_modal_normalization_exact_for_complete_modes(frame):
    w, phi = frame.modes()
    K, M = frame.K(), frame.M()
    wf = np.array([20.0, 100.0, 250.0, 400.0, 600.0, 900.0, 1500.0])
    h = np.array([np.linalg.solve(K - x**2 * M, np.eye(len(K))[3])[5] for x in wf])
    m = 4
    known = (phi[5, m:] * phi[3, m:] / (w[m:][None, :] ** 2 - wf[:, None] ** 2)).sum(1)
    alpha, a1, a2 = fit_modal_normalization(
        (5, 3, wf, h), 2.0 * phi[:, :m], w[:m], known_part=[known]
    )
    assert np.allclose(alpha, 0.25, rtol=1e-6) and abs(a2[0]) < 1e-9 * np.abs(h).max()
