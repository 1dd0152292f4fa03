"""Our stand-in for the Att. 7 Example 1 manipulator arm (Junkins, Pollock & Rahman 1990; its
numbers are not given), shared by tests/identify/test_substructures.py and test_undamped.py:
two flexible appendages (Euler-Bernoulli bending, 4 elements each), a soft rotational spring at
the base (pinned base), a rotational spring at the joint (hinge), and a tip grip with mass 20 kg
and inertia 0.5 kg m^2.  Groups as in the paper: mass I app. 1, II app. 2, III tip inertia, IV
tip mass; stiffness I app. 1, II app. 2, III base spring, IV joint spring.  With the
round-off floor of its eigenvalues (:func:`eigenvalue_roundoff`).
"""

import numpy as np

from flexsat.identify.structural import SubstructureModel
from flexsat.structures import elements as el
from flexsat.structures.sections import Section

ARM = dict(
    L1=5.0,
    L2=4.0,
    n_el=4,
    E=1.45297e11,
    rho=2700.0,
    k_base=1.0209,
    k_joint=18.2436,
    tip_mass=20.0,
    tip_inertia=0.5,
)  # E, k_base, k_joint tuned to modes 1-3 of Table 2


def arm_model():
    """Bending-only arm: pinned base with spring, hinge with spring at the joint, tip grip."""
    a = ARM
    sec = Section.tube(0.05, 0.003)
    bend = [1, 2, 4, 5]
    ne = a["n_el"]
    keys = [("th", 0)] + [(d, i) for i in range(1, ne + 1) for d in ("w", "th")] + [("thb", ne)]
    keys += [(d, i) for i in range(ne + 1, 2 * ne + 1) for d in ("w", "th")]
    idx = {key: i for i, key in enumerate(keys)}
    n = len(keys)
    Kb = [np.zeros((n, n)) for _ in range(4)]
    Mb = [np.zeros((n, n)) for _ in range(4)]
    for e in range(2 * ne):
        g, L = (0, a["L1"] / ne) if e < ne else (1, a["L2"] / ne)
        k = el.beam2d_local_stiffness(a["E"], sec.A, sec.Iz, L)[np.ix_(bend, bend)]
        mm = el.beam2d_local_mass(a["rho"], sec.A, L)[np.ix_(bend, bend)]
        ends = [("w", e), ("thb" if e == ne else "th", e), ("w", e + 1), ("th", e + 1)]
        d = np.array([idx.get(key, -1) for key in ends])
        keep = d >= 0
        Kb[g][np.ix_(d[keep], d[keep])] += k[np.ix_(keep, keep)]
        Mb[g][np.ix_(d[keep], d[keep])] += mm[np.ix_(keep, keep)]
    Kb[2][idx["th", 0], idx["th", 0]] = a["k_base"]
    t = [idx["th", ne], idx["thb", ne]]
    Kb[3][np.ix_(t, t)] = a["k_joint"] * np.array([[1.0, -1.0], [-1.0, 1.0]])
    Mb[2][idx["th", 2 * ne], idx["th", 2 * ne]] = a["tip_inertia"]
    Mb[3][idx["w", 2 * ne], idx["w", 2 * ne]] = a["tip_mass"]
    return SubstructureModel(Kb, Mb, names=("appendage 1", "appendage 2", "III", "IV")), idx


EPS = np.finfo(float).eps


def eigenvalue_roundoff(K, M, phi):
    """Relative first-order change of each eigenvalue when every entry of K and M is perturbed
    by its own round-off, |dK| <= eps |K|, |dM| <= eps |M|: ``eps (|phi|^T |K| |phi| /
    phi^T K phi + |phi|^T |M| |phi| / phi^T M phi)`` (the componentwise condition number of a
    simple eigenvalue of a symmetric definite pencil).  No float64 solver can resolve an
    eigenvalue more finely than this; for the arm's base-spring mode it is 2e-8, where a
    Cholesky-reduced solve (absolute error ~ eps max(lambda), relative 1e-5) is far coarser.
    """
    a = np.abs(phi)
    kinetic = np.einsum("ij,ij->j", phi, M @ phi)
    strain = np.einsum("ij,ij->j", phi, K @ phi)
    return EPS * (
        np.einsum("ij,ij->j", a, np.abs(K) @ a) / strain
        + np.einsum("ij,ij->j", a, np.abs(M) @ a) / kinetic
    )
