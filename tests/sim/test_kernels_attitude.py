"""The three-axis kernel's building blocks (flexsat.sim.kernels_attitude): a propagator entry
and a row of products read the same numbers whether the lanes share one matrix or carry their
own copies (the layouts of a shared and of a dispersed plant). The whole loop is tested
against the Python loop in test_compiled_attitude.py.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from flexsat.sim.kernels_attitude import coefficient, lane_rows

W = 8  # the kernel's lanes per group


@njit(cache=False)
def _entries(A, n_rows, n_cols):
    out = np.empty((n_rows, n_cols, W))
    for i in range(n_rows):
        for j in range(n_cols):
            for lane in range(W):
                out[i, j, lane] = coefficient(A, i, j, lane)
    return out


@njit(cache=False)
def _rows(R, z, out):
    lane_rows(R, z, out, W)


def test_a_shared_matrix_and_the_lanes_copies_give_the_same_coefficients():
    A = np.random.default_rng(0).standard_normal((4, 5))
    copies = np.repeat(A[:, :, None], W, axis=2)
    np.testing.assert_array_equal(_entries(A, 4, 5), _entries(copies, 4, 5))
    np.testing.assert_array_equal(_entries(A, 4, 5)[:, :, 3], A)


def test_shared_row_products_are_the_plain_sums_in_order():
    """A shared matrix's row products: out[i, lane] = Σ_j R[i, j] z[j, lane], summed
    j = 0 .. n − 1 as a plain loop in that order sums them, so bit-identical to it (the
    dispersed layout's row_products keeps the same order: test_kernel_phases)."""
    rng = np.random.default_rng(1)
    R = rng.standard_normal((6, 9))
    z = rng.standard_normal((9, W))
    shared = np.zeros((6, W))
    _rows(R, z, shared)
    want = np.zeros((6, W))
    for i in range(6):
        for j in range(9):
            want[i] += R[i, j] * z[j]
    np.testing.assert_array_equal(shared, want)
