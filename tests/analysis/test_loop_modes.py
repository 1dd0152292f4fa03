"""Closed-loop poles with their modes (flexsat.analysis.loop_modes) on hand-made loops."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag, expm

import control as ct
from flexsat.analysis.frequency_domain import Loop
from flexsat.analysis.loop_modes import closed_loop_poles, damping_table, mode_of_state
from flexsat.input_checks import FieldError

#: ω_n and ζ of an eigenvalue of a 2 × 2 companion block: cond(V) ε with cond ~ 1/√(1 − ζ²)
TOL = 1e-12


def _oscillator(wn: float, zeta: float) -> np.ndarray:
    return np.array([[0.0, 1.0], [-(wn**2), -2 * zeta * wn]])


def _loop(A: np.ndarray, states: tuple[str, ...], dt: float = 0.0) -> Loop:
    return Loop(ct.ss([], [], [], [[0.0]]), "input", A, states, dt)


# a rigid-ish axis at 0.5 rad/s, a flexible mode at 7 rad/s and the law's own pole at −3
BLOCKS = {"theta": (0.5, 0.7), "eta[1]": (7.0, 0.02)}
STATES = ("theta", "theta_dot", "eta[1]", "eta_dot[1]", "law.x[0]")
A_CONT = block_diag(_oscillator(*BLOCKS["theta"]), _oscillator(*BLOCKS["eta[1]"]), [[-3.0]])


def _check(poles):
    assert len(poles) == 5
    for p in poles:
        if p.plant_share < 0.5:  # the law's pole: the plant has no part in it
            assert p.pole == pytest.approx(-3.0, rel=TOL) and p.plant_share == pytest.approx(
                0, abs=TOL
            )
            continue
        wn, zeta = BLOCKS[p.mode]
        assert p.natural_frequency_rad_s == pytest.approx(wn, rel=TOL)
        assert p.damping_ratio == pytest.approx(zeta, rel=1e-10)
        assert p.participation == pytest.approx(1.0, abs=TOL)
        assert p.plant_share == pytest.approx(1.0, abs=TOL)
    # sorted by natural frequency
    wns = [p.natural_frequency_rad_s for p in poles]
    assert wns == sorted(wns)


def test_a_block_diagonal_loop_s_poles_belong_to_their_blocks_with_share_one():
    """Decoupled blocks: each eigenvector lives in one block, so its participation is wholly
    that block's (share 1) and ω_n, ζ are the block's; the law's pole has plant share 0."""
    _check(closed_loop_poles(_loop(A_CONT, STATES)))


def test_a_sampled_loop_maps_its_z_poles_back_to_the_same_s_poles():
    """s = ln z / dt inverts z = e^{s dt} (|Im s| dt = 0.7 · 0.1 < π: no aliasing)."""
    dt = 0.1
    _check(closed_loop_poles(_loop(expm(A_CONT * dt), STATES, dt)))


def test_coupled_states_split_the_participation_and_it_sums_to_one():
    """Mixing the two plant blocks by a similarity leaves the poles but spreads each
    eigenvector over both groups: the largest share is still in (0.5, 1] and, the plant
    carrying every state but the law's, plant_share is 1 for the plant poles."""
    T = np.eye(5)
    T[0, 2] = T[2, 0] = 0.3
    A = T @ A_CONT @ np.linalg.inv(T)
    poles = closed_loop_poles(_loop(A, STATES))
    plant = [p for p in poles if p.plant_share > 0.5]
    assert all(0.5 <= p.participation <= 1.0 + TOL for p in plant)
    assert all(p.plant_share == pytest.approx(1.0, abs=1e-10) for p in plant)
    assert min(p.participation for p in plant) < 0.99  # the coupling is seen
    assert {p.mode for p in plant} == {"theta", "eta[1]"}


def test_an_explicit_grouping_overrides_the_label_rule_and_unknown_states_are_refused():
    poles = closed_loop_poles(_loop(A_CONT, STATES), modes={"bending": ["eta[1]", "eta_dot[1]"]})
    assert {p.mode for p in poles if p.plant_share > 0.5} == {"theta", "bending"}
    with pytest.raises(FieldError, match="modes.*'nope'"):
        closed_loop_poles(_loop(A_CONT, STATES), modes={"m": ["nope"]})
    with pytest.raises(FieldError, match="loop.*no plant states"):
        closed_loop_poles(_loop(np.eye(1), ("law.x",)))


def test_a_rate_label_belongs_to_its_coordinate():
    assert mode_of_state("eta_dot[2]") == "eta[2]"
    assert mode_of_state("theta_dot") == "theta"
    assert mode_of_state("dot_product") == "dot_product"  # only a "_dot" suffix is a rate


def test_the_damping_table_lists_one_line_per_pair_in_hz_and_rad_s():
    """Poles with Im >= 0 only: the two pairs and the real law pole, plus the header."""
    text = damping_table(closed_loop_poles(_loop(A_CONT, STATES)))
    lines = text.splitlines()
    assert len(lines) == 4 and "ω_n (rad/s)" in lines[0] and "f_n (Hz)" in lines[0]
    # the law's pole (plant share 0) is printed under some plant mode's name: pick the plant's
    eta = next(
        r for r in (line.split() for line in lines[1:]) if r[0] == "eta[1]" and r[5] == "1.00"
    )
    assert float(eta[1]) == pytest.approx(7.0, rel=1e-4)  # 5 printed digits
    assert float(eta[2]) == pytest.approx(7.0 / (2 * np.pi), rel=1e-4)
