"""Shared models of the identification tests."""

import numpy as np
import pytest

from flexsat.identify.structural import SubstructureModel, substructures_from_builder
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

ALU = dict(E=70e9, rho=2700.0)


def _material(fk, fm):
    return Material(E=ALU["E"] * fk, rho=ALU["rho"] * fm)


# ------------------------------------------------------------------------------------------------
def _frame_builder(fk, fm, n_el=2):
    s = Structure("portal frame")
    tube = Section.tube(0.05, 0.003)
    xyz = {}
    for level, y in enumerate((0.0, 1.5, 3.0)):
        for col, x in enumerate((0.0, 2.0, 4.0)):
            xyz[10 * level + col] = np.array([x, y, 0.0])
            s.add_node(10 * level + col, xyz[10 * level + col])
    new = iter(range(1000, 2000))

    def member(a, b, g):
        prev = a
        for i in range(1, n_el + 1):
            nxt = b if i == n_el else next(new)
            if nxt != b:
                s.add_node(nxt, xyz[a] + (xyz[b] - xyz[a]) * i / n_el)
            s.add_beam2d(prev, nxt, _material(fk[g], fm[g]), tube)
            prev = nxt

    for level in range(2):
        for col in range(3):
            member(10 * level + col, 10 * (level + 1) + col, 0 if col == 0 else 1)
    for level in (1, 2):
        for col in range(2):
            member(10 * level + col, 10 * level + col + 1, 2)
    for col in range(3):
        s.clamp(col)
    return s.assemble()


@pytest.fixture(scope="session")
def frame():
    return substructures_from_builder(
        _frame_builder, 3, names=("left columns", "other columns", "beams")
    )


@pytest.fixture(scope="session")
def frame_builder():
    return _frame_builder


# ------------------------------------------------------------------------------------------------
def _chain_blocks(n=3, k=1000.0):
    """A fixed-free chain of ``n`` unit masses and springs ``k``: one stiffness block per spring
    (spring 0 to the ground), one mass block per mass."""
    K_blocks, M_blocks = [], []
    for i in range(n):
        K = np.zeros((n, n))
        K[i, i] = k
        if i > 0:
            K[i - 1, i - 1] += k
            K[i - 1, i] = K[i, i - 1] = -k
        K_blocks.append(K)
        M = np.zeros((n, n))
        M[i, i] = 1.0
        M_blocks.append(M)
    return K_blocks, M_blocks


@pytest.fixture(scope="session")
def chain():
    """The 3-dof chain with stiffness-proportional damping blocks (probes of the input checks:
    any small definite model will do)."""
    K_blocks, M_blocks = _chain_blocks()
    return SubstructureModel(K_blocks, M_blocks, [0.01 * K for K in K_blocks])


@pytest.fixture(scope="session")
def calibrated_rig():
    """The calibrated stereo rig of tests/stereo_rig.py (one resection for all test modules)."""
    from stereo_rig import calibrate_rig

    return calibrate_rig()
