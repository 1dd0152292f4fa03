"""Design plants shared by the synthesis tests (H2, H∞, LQG/LTR, HAC/LAC) and the conformance
suite: the TAMU hub with three appendage modes measured by its hub angle, and the Draper/RPL
hub with its collocated tip pairs."""

from __future__ import annotations

import numpy as np

from flexsat.control.generalized_plant import GeneralizedPlant, lqg_plant

#: measurement-noise intensity of the TAMU hub angle, rad² s
TAMU_RN = 1e-4


def tamu_design(n_modes: int = 3):
    """(case, plant, A, B, C, Q): TAMU with ``n_modes`` modes, C the hub angle row, Q weighting
    the angle (100), the rate (10) and every modal coordinate (1)."""
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.linear_model import plant_state_space

    case = tamu(n_modes=n_modes)
    plant = case.model()
    P = plant_state_space(plant)
    A, B = np.asarray(P.A), np.asarray(P.B)
    C = np.asarray(P.C)[[list(P.output_labels).index("theta")]]
    n = A.shape[0]
    Q = np.eye(n)
    Q[0, 0], Q[n // 2, n // 2] = 100.0, 10.0
    return case, plant, A, B, C, Q


def tamu_generalized(n_modes: int = 3):
    """The LQG generalized plant of the TAMU design: unit torque noise, R = 1."""
    _, _, A, B, C, Q = tamu_design(n_modes)
    return lqg_plant(
        A,
        B,
        C,
        Q,
        np.eye(1),
        np.eye(1),
        TAMU_RN * np.eye(1),
        controls=("torque",),
        measurements=("theta",),
    )


DRAPER_PAIRS = (("u2_tips_1_3", "rot_tips_1_3_dot"), ("u3_tips_2_4", "rot_tips_2_4_dot"))


def draper_design(n_modes: int = 6, damping: float = 0.002):
    """(case, plant, P, Q): the Draper/RPL modal plant (``damping`` on every elastic mode), its
    StateSpace and the HAC weight (hub angle 100, rate 10, modes 1)."""
    from flexsat.cases.draper_rpl import draper_rpl
    from flexsat.dynamics.linear_model import plant_state_space

    case = draper_rpl()
    plant = case.plant(n_modes=n_modes, damping=damping)
    P = plant_state_space(plant)
    n = P.nstates
    Q = np.eye(n)
    Q[0, 0], Q[n // 2, n // 2] = 100.0, 10.0
    return case, plant, P, Q


def random_plant(seed: int) -> GeneralizedPlant:
    """A random generalized plant (5 states, 3 w, 2 u, 4 z, 2 y) with the cross terms D12 and D21
    and D11 = D22 = 0 (what both syntheses take)."""
    rng = np.random.default_rng(seed)
    n, nw, nu, nz, ny = 5, 3, 2, 4, 2
    return GeneralizedPlant(
        rng.normal(size=(n, n)),
        rng.normal(size=(n, nw)),
        rng.normal(size=(n, nu)),
        rng.normal(size=(nz, n)),
        rng.normal(size=(ny, n)),
        np.zeros((nz, nw)),
        rng.normal(size=(nz, nu)),
        rng.normal(size=(ny, nw)),
        np.zeros((ny, nu)),
        tuple(f"w{i}" for i in range(nw)) + ("u0", "u1"),
        tuple(f"z{i}" for i in range(nz)) + ("y0", "y1"),
    )
