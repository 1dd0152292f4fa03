"""Reference Markov parameters for the realization tests (tests/identify/test_era.py,
test_markov.py, test_era_inputs.py): the exact pulse response of a ZOH-discretized model,
the FRF frequency grid, and a two-mode SISO system (2 and 7 rad/s, 2 % damping, 100 Hz)."""

import numpy as np
from scipy.linalg import expm
from scipy.signal import cont2discrete

from flexsat.identify.excitation import sensor_matrices

DT = 0.01  # sampling interval of the two-mode system, s


def discrete_markov(grid, sensors, inputs, dt, n):
    A, B, C, D = sensor_matrices(grid, sensors, inputs)
    ns, r = B.shape
    M = np.zeros((ns + r, ns + r))
    M[:ns, :ns], M[:ns, ns:] = A * dt, B * dt
    E = expm(M)
    Ad, Bd = E[:ns, :ns], E[:ns, ns:]
    Y, P = [D], Bd
    for _ in range(n):
        Y.append(C @ P)
        P = Ad @ P
    return np.array(Y)


def frf_grid(rate, period):
    n = int(round(rate * period))
    return np.arange(n // 2 + 1) / period


def two_mode_system():
    w, z = np.array([2.0, 7.0]), 0.02
    A = np.zeros((4, 4))
    A[:2, 2:] = np.eye(2)
    A[2:, :2], A[2:, 2:] = -np.diag(w**2), -np.diag(2 * z * w)
    B, C = np.array([[0.0], [0.0], [1.0], [1.0]]), np.array([[1.0, 0.5, 0.0, 0.0]])
    Ad, Bd, Cd, Dd, _ = cont2discrete((A, B, C, np.zeros((1, 1))), DT)
    return Ad, Bd, Cd, Dd
