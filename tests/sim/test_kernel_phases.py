"""The phases of the compiled step (flexsat.sim.kernel_phases), called on their own: the row
products of either layout give each row's sum in the order j = 0 .. n − 1, bit for bit (what
makes a case's numbers the same in a group of 1 or 8 lanes), and the layout helpers place
every entry where the products read it."""

import numpy as np
import pytest

from flexsat.sim.kernel_phases import BLOCK, row_count, row_entry, row_products, rows_shape


def _laid_out(M: np.ndarray, W: int) -> np.ndarray:
    """M (W, R, n), one matrix per lane, in the layout of rows_shape."""
    _, R, n = M.shape
    Mt = np.zeros(rows_shape(R, n, W))
    for i in range(R):
        for j in range(n):
            a, b = row_entry(i, j, n, W)
            Mt[a, b, :] = M[:, i, j]
    return Mt


def _in_order(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Σ_j M[i, j] x[j] summed left to right, one float at a time."""
    out = np.zeros(M.shape[0])
    for i in range(M.shape[0]):
        s = 0.0
        for j in range(M.shape[1]):
            s += M[i, j] * x[j]
        out[i] = s
    return out


@pytest.mark.parametrize("W", [1, 8])
@pytest.mark.parametrize("R, n", [(1, 1), (7, 5), (11, 22), (16, 3)])
def test_row_products_are_the_in_order_sums_of_either_layout(W, R, n):
    rng = np.random.default_rng(R * 100 + n)
    M = rng.standard_normal((W, R, n)) * 10.0 ** rng.integers(-8, 8, (W, R, n))
    x = rng.standard_normal((n, W))
    Mt = _laid_out(M, W)
    assert row_count(Mt, n) >= R and (W > 1 or row_count(Mt, n) % BLOCK == 0)
    out = np.full((row_count(Mt, n), W), np.nan)
    row_products(Mt, x, out, W)
    for lane in range(W):
        np.testing.assert_array_equal(out[:R, lane], _in_order(M[lane], x[:, lane]))
    if W == 1:  # the padding rows are zero rows
        assert not out[R:].any()
