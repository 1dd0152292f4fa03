"""Damping identification (:mod:`flexsat.identify.structural.damping`, Att. 7 Eqs. 10-24):
proportional damping of the portal frame, eigenvalue pairing by frequency."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify.structural import (
    SubstructureModel,
    damped_eigenvalues,
    identify_damping,
)

pytestmark = pytest.mark.numerics  # tolerances near round-off: re-run on other BLAS kernels


# ------------------------------------------------------------------------------------------------
# measured eigenvalues are paired with the model modes by frequency, not by position


@pytest.fixture(scope="module")
def proportional(frame):
    """The frame with C = a M + b K (a = 0.3 1/s, b = 2e-4 s) and its first six eigenvalues.

    Proportional damping keeps the undamped modes, so Eq. 24 is exact here: sigma_r =
    -(a + b w_r^2)/2 and the identified r is (a, b) to the eigen-solve's rounding."""
    damped = SubstructureModel(frame.K_blocks, frame.M_blocks, [frame.M(), frame.K()])
    lam = damped_eigenvalues(frame.K(), frame.M(), 0.3 * frame.M() + 2e-4 * frame.K(), n_modes=6)
    return damped, lam


def test_damping_eigenvalues_in_any_order_are_matched_by_frequency(proportional):
    damped, lam = proportional
    ref = identify_damping(damped, lam)
    # exact first-order theory; eigenvalues to ~1e-13 relative -> 1e-9 on r
    np.testing.assert_allclose(ref.r, [0.3, 2e-4], rtol=1e-9)
    np.testing.assert_array_equal(ref.mode_indices, np.arange(6))
    perm = [3, 0, 5, 1, 4, 2]  # modes 3 and 4 are only 3 % apart (348 and 360 rad/s)
    out = identify_damping(damped, lam[perm])
    np.testing.assert_allclose(out.r, ref.r, rtol=1e-12)
    np.testing.assert_array_equal(out.mode_indices, perm)
    np.testing.assert_allclose(out.predicted_real_parts, ref.predicted_real_parts[perm], rtol=1e-12)
    np.testing.assert_allclose(out.eigenvalues, lam[perm], rtol=1e-9)
    # given in that order, the pairing stated by mode_indices is the same
    np.testing.assert_allclose(
        identify_damping(damped, lam[perm], mode_indices=perm).r, ref.r, rtol=1e-12
    )
    # the conjugates carry the same frequencies
    np.testing.assert_allclose(identify_damping(damped, np.conj(lam[perm])).r, ref.r, rtol=1e-12)


def test_damping_eigenvalues_that_do_not_match_the_model_are_refused(proportional):
    damped, lam = proportional
    w, _ = damped.modes()
    with pytest.raises(
        ValueError,
        match=r"^mode_indices: measured_eigenvalues\[0\] \(natural "
        r"frequency 347\.\d+ rad/s\) is nearest model mode 3 "
        r".* but mode_indices pairs it with mode 0",
    ):
        identify_damping(damped, lam[[3, 0, 5, 1, 4, 2]], mode_indices=range(6))
    # a measured mode between two model modes (geometric mean of modes 1 and 2): missing
    between = lam.copy()
    between[1] = -1.0 + 1j * np.sqrt(w[1] * w[2])
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues\[1\]: natural frequency .* has "
        r"no clearly nearest model mode \(modes 1 at .* and 2 at",
    ):
        identify_damping(damped, between)
    twice = lam.copy()
    twice[2] = lam[1] * 1.01
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues\[1\] and \[2\] are both nearest "
        r"model mode 1 ",
    ):
        identify_damping(damped, twice)
    with pytest.raises(
        ValueError,
        match=r"^measured_eigenvalues: give every eigenvalue as sigma "
        r"\+ i w with w != 0",
    ):
        identify_damping(damped, np.append(lam[:3], -1.0 + 0j))
    with pytest.raises(ValueError, match=r"^mode_indices: each model mode at most once"):
        identify_damping(damped, lam, mode_indices=[0, 1, 2, 3, 4, 4])


def test_damping_real_parts_are_paired_in_order(proportional):
    # real parts carry no frequency: the documented pairing is by position (lowest modes)
    damped, lam = proportional
    out = identify_damping(damped, lam.real)
    np.testing.assert_allclose(out.r, [0.3, 2e-4], rtol=1e-9)
    np.testing.assert_array_equal(out.mode_indices, np.arange(6))
