"""Tests of flexsat.structures.modal_model.

Finite-element inputs come from flexsat.structures.fem: pin-jointed trusses of point masses on
massless rods (translational dofs only) and a free plane grid. For those every modal quantity
has an independent closed form: mass properties are sums over the masses (line integrals for
the grid), the modal momentum is L = Σ_k m_k (φ_k, r_k × φ_k), and with all modes kept
Σ_i L_iᵀ L_i = RᵀMR and the modal flexibility Σ φ φᵀ / ω² is K⁻¹.

Tolerances: the FE eigen-solve (Φᵀ M Φ = I to round-off) and RᵀMR are backward stable, so the
identities between matrices of size <= 18 hold to ~1e-15 relative (measured, see each test);
RTOL = 1e-10 leaves ample margin and still catches any modelling error (a wrong sign, factor or
term is O(1)). Quantities that are copied or rearranged (save/load) are compared bitwise.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from flexsat.dynamics.hub_appendage import HubAppendage, HubAppendageParams
from flexsat.structures.fem import Structure
from flexsat.structures.modal_model import ModalModel, hub_appendage_matrices
from flexsat.structures.sections import Material

RTOL = 1e-10
SPRING = Material(E=1e9, rho=0.0)  # massless rods: all mass is in the point masses


# ------------------------------------------------------------------------------------------------
# finite-element models
def truss(coordinates: dict, masses: dict, members, clamped=(), rigid_body_modes=None):
    """All modes of point masses joined by massless rods of axial stiffness k: (a, b, k)."""
    structure = Structure("truss")
    for nid, xyz in coordinates.items():
        structure.add_node(nid, xyz)
    for a, b, k in members:
        length = np.linalg.norm(np.subtract(coordinates[b], coordinates[a]))
        structure.add_rod(a, b, SPRING, area=k * length / SPRING.E)
    for nid, m in masses.items():
        structure.add_mass(nid, m)
    for nid in clamped:
        structure.clamp(nid)
    assembly = structure.assemble()
    return assembly.modes(assembly.n_dofs, rigid_body_modes=rigid_body_modes)


def tower():
    """Three-level triangular truss tower, bottom level clamped: 18 dofs, no mechanism."""
    coords, masses, members = {}, {}, []
    for level in range(3):
        for j in range(3):
            a = 2 * np.pi * j / 3 + 0.3 * level
            nid = 10 * level + j + 1
            coords[nid] = (np.cos(a), np.sin(a), 1.2 * level)
            masses[nid] = 1.0 + 0.37 * nid
    for level in range(1, 3):
        for j in range(3):
            here, nxt, below = 10 * level + j + 1, 10 * level + (j + 1) % 3 + 1, 10 * (level - 1)
            members += [
                (here, nxt, 2e4 + 1e3 * j),
                (below + j + 1, here, 3e4),
                (below + (j + 1) % 3 + 1, here, 2.5e4 + 2e3 * level),
            ]
    bottom = {nid: m for nid, m in masses.items() if nid < 10}  # clamped: carry no dofs
    free_masses = {nid: m for nid, m in masses.items() if nid > 10}
    return truss(coords, masses, members, clamped=tuple(bottom)), coords, free_masses


def tetrahedron():
    """Free tetrahedron of four point masses away from the origin: 6 rigid + 6 elastic modes."""
    coords = {1: (1.0, 0.5, 0.2), 2: (2.5, 0.4, 0.1), 3: (1.7, 1.9, 0.3), 4: (1.8, 0.9, 1.6)}
    masses = {1: 1.0, 2: 2.0, 3: 1.5, 4: 0.7}
    members = [(a, b, 1e3 * (a + b)) for a in range(1, 5) for b in range(a + 1, 5)]
    return truss(coords, masses, members, rigid_body_modes=6), coords, masses


def two_point_masses(coords):
    """Two masses (2 kg, 5 kg) and one rod: 5 rigid modes (no rotation about the rod axis)."""
    masses = {1: 2.0, 2: 5.0}
    return truss(coords, masses, [(1, 2, 1e3)], rigid_body_modes=5), masses


def lumped_sums(coords, masses, model: ModalModel, reference):
    """Σ_k m_k φ_k and Σ_k m_k (r_k − p) × φ_k over the nodes, shape (m, 6)."""
    L = np.zeros((model.n_modes, 6))
    for nid, m in masses.items():
        phi = model.shapes[:, list(model.node_ids).index(nid), :3]
        r = np.asarray(coords[nid]) - reference
        L[:, :3] += m * phi
        L[:, 3:] += m * np.cross(r, phi)
    return L


def skew(v):
    x, y, z = v
    return np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])


def point_mass_properties(coords, masses):
    m = sum(masses.values())
    c = sum(masses[i] * np.asarray(coords[i]) for i in masses) / m

    def inertia(about):
        return sum(
            masses[i] * (np.dot(d, d) * np.eye(3) - np.outer(d, d))
            for i in masses
            for d in [np.asarray(coords[i]) - about]
        )

    return m, c, inertia


def synthetic(n_modes=3, boundary="free", seed=0) -> ModalModel:
    """Two point masses (2 kg and 3 kg) at nodes 7 and 9 with random small shapes."""
    rng = np.random.default_rng(seed)
    coords = {7: (0.0, 0.0, 0.0), 9: (1.0, 2.0, 0.5)}
    masses = {7: 2.0, 9: 3.0}
    rigid = np.zeros((6, 6))
    for nid, m in masses.items():
        S = skew(coords[nid])
        rigid += m * np.block([[np.eye(3), -S], [S, -S @ S]])
    return ModalModel(
        node_ids=[7, 9],
        coordinates=[coords[7], coords[9]],
        frequencies=np.linspace(1.0, 3.0, n_modes),
        damping=0.02,
        shapes=0.1 * rng.standard_normal((n_modes, 2, 6)),
        rigid_mass=rigid,
        participation=np.zeros((n_modes, 6)),
        boundary=boundary,
    )


def vars_of(model: ModalModel) -> dict:
    names = (
        "node_ids",
        "coordinates",
        "frequencies",
        "damping",
        "shapes",
        "rigid_mass",
        "participation",
        "reference",
        "boundary",
    )
    return {name: getattr(model, name) for name in names}


# ------------------------------------------------------------------------------------------------
# construction
def _bad_rigid(edit):
    rigid = synthetic().rigid_mass.copy()
    edit(rigid)
    return rigid


def _set(rigid, idx, value):
    rigid[idx] = value


# positive definite (m = 5 kg, I = diag(1, 2, 3)) but a rotation–translation block with a
# diagonal entry, which no [c×] has
NOT_SKEW = np.diag([5.0, 5.0, 5.0, 1.0, 2.0, 3.0])
NOT_SKEW[0, 3] = NOT_SKEW[3, 0] = 0.1

CONSTRUCTION_ERRORS = [
    ("node_ids", dict(node_ids=[7, 7]), "unique"),
    ("node_ids", dict(node_ids=[7, 9.5]), "integers"),
    ("coordinates", dict(coordinates=np.zeros((3, 3))), "shape"),
    ("coordinates", dict(coordinates=[[0, 0, 0], [1, np.nan, 0]]), "finite"),
    ("frequencies", dict(frequencies=[1.0, -2.0, 3.0]), ">= 0"),
    ("frequencies", dict(frequencies=[1.0, 3.0, 2.0]), "ascending"),
    (
        "frequencies",
        dict(frequencies=[], shapes=np.zeros((0, 2, 6)), participation=np.zeros((0, 6))),
        "at least one",
    ),
    ("damping", dict(damping=[0.01, -0.01, 0.0]), ">= 0"),
    ("damping", dict(damping=[0.01, 0.02]), "shape"),
    ("shapes", dict(shapes=np.zeros((3, 2, 3))), "shape"),
    ("shapes", dict(shapes=np.full((3, 2, 6), np.inf)), "finite"),
    ("rigid_mass", dict(rigid_mass=np.eye(3)), "shape"),
    (
        "rigid_mass",
        dict(rigid_mass=_bad_rigid(lambda r: _set(r, (3, 4), r[3, 4] + 0.5))),
        "symmetric",
    ),
    ("rigid_mass", dict(rigid_mass=_bad_rigid(lambda r: _set(r, (5, 5), -1.0))), "semi-definite"),
    ("rigid_mass", dict(rigid_mass=_bad_rigid(lambda r: _set(r, (1, 1), 6.0))), "m·I"),
    ("rigid_mass", dict(rigid_mass=np.diag([0, 0, 0, 1.0, 1.0, 1.0])), "total mass"),
    ("rigid_mass", dict(rigid_mass=NOT_SKEW), "[c×]"),
    ("participation", dict(participation=np.zeros((2, 6))), "shape"),
    ("participation", dict(participation=np.full((3, 6), 2.0)), "Bessel"),
    ("reference", dict(reference=(0.0, 0.0)), "shape"),
    ("boundary", dict(boundary="clamped"), "one of"),
]


@pytest.mark.parametrize(("field", "change", "rule"), CONSTRUCTION_ERRORS)
def test_construction_errors_name_the_field_and_rule(field, change, rule):
    with pytest.raises(ValueError) as err:
        ModalModel(**{**vars_of(synthetic()), **change})
    assert str(err.value).startswith(f"{field}:"), str(err.value)
    assert rule in str(err.value)


def test_arrays_are_read_only_copies():
    shapes = np.ones((3, 2, 6)) * 0.01
    base = synthetic()
    model = ModalModel(
        base.node_ids,
        base.coordinates,
        base.frequencies,
        0.0,
        shapes,
        base.rigid_mass,
        base.participation,
    )
    shapes[:] = 5.0
    assert np.all(model.shapes == 0.01)
    with pytest.raises(ValueError):
        model.frequencies[0] = 0.0
    assert np.array_equal(model.damping, np.zeros(3))  # scalar damping broadcast


# ------------------------------------------------------------------------------------------------
# mass properties
def test_two_point_masses_mass_properties_by_hand():
    r1, r2 = np.array([0.4, -0.3, 0.2]), np.array([1.9, 0.8, -0.5])
    modes, _ = two_point_masses({1: r1, 2: r2})
    model = ModalModel.from_fe(modes, reference=(0.1, 0.2, 0.3))
    # by hand: m = 7 kg, c = (2 r1 + 5 r2) / 7, I_c = Σ m (|d|² I − d dᵀ), d = r − c
    c = (2 * r1 + 5 * r2) / 7
    d1, d2 = r1 - c, r2 - c
    I_c = sum(mk * (d @ d * np.eye(3) - np.outer(d, d)) for mk, d in ((2, d1), (5, d2)))
    assert model.total_mass == pytest.approx(7.0, rel=RTOL)
    assert np.allclose(model.center_of_mass, c, rtol=0, atol=RTOL)
    assert np.allclose(model.inertia(), I_c, rtol=0, atol=RTOL * np.abs(I_c).max())
    # the line through both masses is a principal axis with no inertia
    axis = (d2 - d1) / np.linalg.norm(d2 - d1)
    assert np.allclose(model.inertia() @ axis, 0, rtol=0, atol=RTOL * np.abs(I_c).max())
    assert model.boundary == "free"  # inferred: K R = 0


def test_parallel_axis_theorem():
    modes, coords, masses = tetrahedron()
    model = ModalModel.from_fe(modes, reference=(0.5, -0.2, 0.1))
    m, c, inertia = point_mass_properties(coords, masses)
    assert np.allclose(model.center_of_mass, c, rtol=0, atol=RTOL)
    for about in ([0.0, 0.0, 0.0], [3.0, -1.0, 2.0], c, model.reference):
        I = model.inertia(about)
        assert np.allclose(I, inertia(np.asarray(about)), rtol=0, atol=RTOL * np.abs(I).max())
        # I_a = I_c + m (|a − c|² I − (a − c)(a − c)ᵀ)
        d = np.asarray(about) - c
        assert np.allclose(
            I,
            model.inertia() + m * (d @ d * np.eye(3) - np.outer(d, d)),
            rtol=0,
            atol=RTOL * np.abs(I).max(),
        )
    assert np.array_equal(model.inertia(model.reference), model.rigid_mass[3:, 3:])


def test_masses_on_an_axis_through_the_reference():
    """No inertia about the x axis at the reference (R's rx column is 0), yet all translations
    exist, so the parallel-axis theorem still applies about x away from that axis."""
    coords = {1: (1.0, 0.0, 0.0), 2: (3.0, 0.0, 0.0)}
    modes, masses = two_point_masses(coords)
    model = ModalModel.from_fe(modes)
    assert model.rigid_mass[3, 3] == 0
    _, _, inertia = point_mass_properties(coords, masses)
    about = np.array([0.5, 1.0, -2.0])
    expected = inertia(about)
    assert np.allclose(model.inertia(about), expected, rtol=0, atol=RTOL * np.abs(expected).max())


def test_plane_grid_keeps_absent_rigid_motions_at_zero():
    """A free grid in the XY plane (dofs uz, rx, ry) has no rigid tx, ty, rz. Its mass is on
    members (μ kg/m, consistent mass, exact for the rigid motions), so by hand, per member
    from p to q: mass μℓ, first moment μℓ (p + q)/2, second moment μℓ (d dᵀ + Δ Δᵀ/12) with
    d the mid-point and Δ = q − p."""
    coords = {1: (0.5, 0.2, 0.0), 2: (2.5, 0.2, 0.0), 3: (2.5, 1.7, 0.0), 4: (0.5, 1.7, 0.0)}
    members = [(1, 2, 2.0), (2, 3, 1.0), (3, 4, 2.0), (4, 1, 1.0), (1, 3, 0.5)]
    structure = Structure("grid")
    for nid, xyz in coords.items():
        structure.add_node(nid, xyz)
    for a, b, mu in members:
        structure.add_grid(a, b, EI=1e3, GJ=5e2, mass_per_length=mu)
    assembly = structure.assemble()
    reference = np.array([1.0, 1.0, 0.0])
    model = ModalModel.from_fe(
        assembly.modes(assembly.n_dofs, rigid_body_modes=3), reference=reference
    )
    about = np.array([-1.0, 2.0, 0.0])
    m, first, P = 0.0, np.zeros(3), np.zeros((3, 3))
    for a, b, mu in members:
        p, q = np.asarray(coords[a]), np.asarray(coords[b])
        ell = np.linalg.norm(q - p)
        d, delta = (p + q) / 2 - about, q - p
        m += mu * ell
        first += mu * ell * (p + q) / 2
        P += mu * ell * (np.outer(d, d) + np.outer(delta, delta) / 12)
    expected = np.trace(P) * np.eye(3) - P
    expected[2, :] = expected[:, 2] = 0.0  # no rz in the model
    assert model.total_mass == pytest.approx(m, rel=RTOL)
    assert np.allclose(model.center_of_mass, first / m, rtol=0, atol=RTOL)
    assert np.allclose(model.inertia(about), expected, rtol=0, atol=RTOL * expected.max())
    assert np.all(np.diag(model.rigid_mass)[[0, 1, 5]] == 0)
    assert np.all(model.participation[:, [0, 1, 5]] == 0)
    assert model.boundary == "free" and model.elastic().n_modes == model.n_modes - 3


# ------------------------------------------------------------------------------------------------
# participation
@pytest.mark.parametrize("make", [tetrahedron, tower])
def test_participation_is_the_sum_over_lumped_masses(make):
    modes, coords, masses = make()
    reference = np.array([0.3, -0.4, 0.2])
    model = ModalModel.from_fe(modes, damping=0.01, reference=reference)
    assert model.boundary == ("free" if make is tetrahedron else "cantilevered")
    L = lumped_sums(coords, masses, model, reference)
    scale = np.abs(L).max()
    assert np.allclose(model.participation, L, rtol=0, atol=RTOL * scale)
    if make is tetrahedron:  # elastic modes of a free body carry no momentum
        assert np.abs(model.elastic().participation).max() < RTOL * scale
        assert model.elastic().n_modes == model.n_modes - 6


@pytest.mark.parametrize("make", [tetrahedron, tower])
def test_complete_modal_set_gives_bessel_equality(make):
    """With all modes kept Σ L_iᵀ L_i = R_aᵀ M_aa R_a over the active dofs (completeness). For a
    free body that is the rigid mass; for the clamped tower the rigid mass also holds the
    mass sitting on the clamped ring (hybrid coordinates: it moves with the carrier)."""
    modes = make()[0]
    reference = (0.2, 0.1, -0.3)
    model = ModalModel.from_fe(modes, reference=reference)
    L, Mrr = model.participation, model.rigid_mass
    R = modes.assembly.rigid_body_vectors(reference)
    active = R.T @ (modes.assembly.M @ R)
    d = np.sqrt(np.diag(Mrr))
    assert np.allclose((L.T @ L) / np.outer(d, d), active / np.outer(d, d), rtol=0, atol=RTOL)
    gap = np.linalg.eigvalsh((Mrr - active) / np.outer(d, d))
    if make is tetrahedron:
        assert np.abs(gap).max() < RTOL
    else:
        assert gap.min() > -RTOL and gap.max() > 0.1  # the ring's mass is in Mrr only


# ------------------------------------------------------------------------------------------------
# influence vectors
def test_modal_flexibility_is_the_inverse_stiffness():
    """Static response with all modes: Σ c_i b_i / ω_i² = (K⁻¹)_ab for any force/sensor pair."""
    modes, _, _ = tower()
    model = ModalModel.from_fe(modes)
    assembly = modes.assembly
    flex = np.linalg.inv(assembly.K.toarray())
    inv_w2 = 1.0 / model.frequencies**2
    for (na, da), (nb, db) in [((21, "ux"), (21, "ux")), ((12, "uz"), (23, "uy"))]:
        b = model.force_input(nb, db[1])
        c = model.displacement_output(na, da[1])
        expected = flex[assembly.index(na, da), assembly.index(nb, db)]
        assert c @ (inv_w2 * b) == pytest.approx(expected, rel=RTOL)
    # an oblique direction is normalised: (x + y)/√2
    oblique = model.force_input(22, [3.0, 3.0, 0.0])
    expected = (model.force_input(22, "x") + model.force_input(22, "y")) / np.sqrt(2)
    assert np.allclose(oblique, expected, rtol=0, atol=1e-15)


def test_influence_vectors_read_the_shapes():
    model = synthetic(n_modes=4)
    phi7, phi9 = model.shapes[:, 0], model.shapes[:, 1]
    assert np.array_equal(model.force_input(9, "y"), phi9[:, 1])
    assert np.array_equal(model.torque_input(7, "z"), phi7[:, 5])
    assert np.allclose(model.torque_input(7, [0, 0, -2.0]), -phi7[:, 5], rtol=0, atol=1e-15)
    several = model.force_input(9, np.eye(3))
    assert several.shape == (4, 3) and np.array_equal(several, phi9[:, :3])
    assert model.rotation_output(9, ["x", "z"]).shape == (4, 2)
    pair = model.moment_pair(7, 9, "x")
    assert np.allclose(pair, phi9[:, 3] - phi7[:, 3], rtol=0, atol=1e-15)
    # collocation: each sensor is the transpose of its actuator
    assert np.array_equal(model.strain_output(7, 9, "x"), pair)
    assert np.array_equal(model.displacement_output(7, "z"), model.force_input(7, "z"))
    assert np.array_equal(model.rotation_output(9, "y"), model.torque_input(9, "y"))


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda m: m.force_input(8, "x"), "node"),
        (lambda m: m.force_input("7", "x"), "node"),
        (lambda m: m.force_input(7, [0, 0, 0]), "direction"),
        (lambda m: m.force_input(7, "w"), "direction"),
        (lambda m: m.torque_input(7, [1.0, 2.0]), "axis"),
        (lambda m: m.torque_input(7, 2.0), "axis"),
        (lambda m: m.force_input(7, ["x", [0, 0]]), "direction"),
        (lambda m: m.moment_pair(7, 7, "x"), "node_b"),
        (lambda m: m.moment_pair(7, 10, "x"), "node_b"),
        (lambda m: m.strain_output(3, 9, "z"), "node_a"),
        (lambda m: m.truncate(), "truncate"),
        (lambda m: m.truncate(max_frequency=0.5), "truncate"),
        (lambda m: m.truncate(n_modes=0), "n_modes"),
        (lambda m: m.elastic(rigid_frequency=10.0), "elastic"),
        (lambda m: m.to_second_order([np.ones(2)]), "inputs[0]"),
        (lambda m: m.to_second_order([], [(np.ones(3), "acceleration")]), "outputs[0]"),
        (lambda m: m.to_second_order([], [np.ones(3)]), "outputs[0]"),
        (lambda m: m.to_second_order([], [(np.ones(2), "velocity")]), "outputs[0]"),
        (lambda m: m.inertia(about=(1.0, 2.0)), "about"),
    ],
)
def test_helper_errors_name_the_argument(call, field):
    with pytest.raises(ValueError) as err:
        call(synthetic())
    assert str(err.value).startswith(f"{field}:"), str(err.value)


def test_truncate_and_elastic():
    modes, _, _ = tetrahedron()
    model = ModalModel.from_fe(modes, damping=np.linspace(0, 0.1, 12))
    assert np.all(model.frequencies[:6] == 0) and model.frequencies[6] > 10
    elastic = model.elastic()
    assert elastic.n_modes == 6
    assert np.array_equal(elastic.frequencies, model.frequencies[6:])
    assert np.array_equal(elastic.damping, model.damping[6:])
    assert np.array_equal(elastic.shapes, model.shapes[6:])
    assert np.array_equal(elastic.rigid_mass, model.rigid_mass)
    w = model.frequencies
    assert model.truncate(n_modes=8).n_modes == 8
    assert np.array_equal(model.truncate(max_frequency=w[9]).frequencies, w[:10])
    assert model.truncate(n_modes=8, max_frequency=w[9]).n_modes == 8
    assert model.truncate(n_modes=20, max_frequency=w[6]).n_modes == 7


# ------------------------------------------------------------------------------------------------
# system matrices
def test_second_order_matrices():
    model = synthetic(n_modes=3)
    b1, b2 = model.force_input(9, "x"), model.torque_input(7, np.eye(3)[:2])
    c1, c2 = model.displacement_output(9, "x"), model.strain_output(7, 9, "z")
    M, D, K, B, Cq, Cv = model.to_second_order([b1, b2], [(c1, "displacement"), (c2, "velocity")])
    w, z = model.frequencies, model.damping
    assert np.array_equal(M, np.eye(3))
    assert np.array_equal(np.diag(D), 2 * z * w) and np.count_nonzero(D - np.diag(np.diag(D))) == 0
    assert np.array_equal(np.diag(K), w**2)
    assert np.array_equal(B, np.column_stack([b1, b2]))
    assert np.array_equal(Cq, np.vstack([c1, np.zeros(3)]))
    assert np.array_equal(Cv, np.vstack([np.zeros(3), c2]))


def test_statespace_matches_the_second_order_model():
    model = ModalModel(
        **{
            **vars_of(synthetic(n_modes=3)),
            "frequencies": [2.0, 15.0, 40.0],
            "damping": [0.0, 0.05, 0.3],
        }
    )
    b = model.force_input(9, "y")
    c = model.displacement_output(9, "y")
    sys = model.to_statespace([b], [(c, "displacement"), (c, "velocity")])
    w, z = model.frequencies, model.damping
    damped = w * np.sqrt(1 - z**2)
    expected = np.concatenate([-z * w + 1j * damped, -z * w - 1j * damped])
    poles = np.sort_complex(sys.poles())
    assert np.allclose(poles, np.sort_complex(expected), rtol=0, atol=1e-12 * w.max())
    _, D, K, B, Cq, Cv = model.to_second_order([b], [(c, "displacement"), (c, "velocity")])
    for s in (0.3j, 7.0 + 2.0j, 40.0j):
        G = (Cq + s * Cv) @ np.linalg.solve(s**2 * np.eye(3) + s * D + K, B)
        assert np.allclose(sys(s), G, rtol=1e-12, atol=0)
    assert sys.nstates == 6 and sys.ninputs == 1 and sys.noutputs == 2


# ------------------------------------------------------------------------------------------------
# HubAppendage
def hub_model(n, tip_inertia=0.0, damping=0.004):
    params = HubAppendageParams(
        hub_inertia=0.35,
        n_appendages=n,
        hub_radius=0.14,
        length=1.16,
        EI=23.6,
        rho=1.3,
        tip_mass=1.7,
        tip_inertia=tip_inertia,
        damping=damping,
    )
    return HubAppendage(params, n_modes=6)


@pytest.mark.parametrize("n", [1, 3, 4])
def test_hub_appendage_round_trip_reproduces_the_hybrid_matrices(n):
    """HubAppendage → ModalModel → hub_appendage_matrices = Tᵀ (M, D, K) T, T = diag(1, I/√n)."""
    hub = hub_model(n, tip_inertia=0.01)
    modal = ModalModel.from_hub_appendage(hub)
    M, D, K = hub_appendage_matrices(modal, hub.params.hub_inertia)
    T = np.diag(np.concatenate([[1.0], np.full(hub.n_modes, n**-0.5)]))
    for got, ref in ((M, hub.mass_matrix), (D, hub.damping_matrix), (K, hub.stiffness_matrix)):
        ref = T @ ref @ T
        assert np.allclose(got, ref, rtol=0, atol=1e-14 * np.abs(ref).max())
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)[1:]
    assert np.allclose(np.sqrt(lam), hub.frequencies(), rtol=1e-12, atol=0)
    assert np.array_equal(modal.frequencies, hub.cantilever_frequencies)


@pytest.mark.parametrize("n", [1, 4])
def test_hub_appendage_export_physics(n):
    hub = hub_model(n, tip_inertia=0.01)
    p = hub.params
    modal = ModalModel.from_hub_appendage(hub, stations=[0.0, 0.5, p.length])
    assert modal.boundary == "cantilevered" and modal.n_modes == hub.n_modes
    assert np.array_equal(modal.damping, hub.damping_ratios)
    # rigid mass: n (ρL + m) kg, inertia n I_b about z, centre of mass on the hub axis for n >= 2
    assert modal.total_mass == pytest.approx(n * (p.rho * p.length + p.tip_mass), rel=1e-14)
    assert modal.rigid_mass[5, 5] == pytest.approx(n * p.appendage_inertia, rel=1e-14)
    if n == 1:
        l0, l = p.hub_radius, p.tip_radius
        x_c = (p.rho * (l**2 - l0**2) / 2 + p.tip_mass * l) / (p.rho * p.length + p.tip_mass)
        assert np.allclose(modal.center_of_mass, [x_c, 0, 0], rtol=0, atol=1e-14)
    else:
        assert np.allclose(modal.center_of_mass, 0, rtol=0, atol=1e-14)
    # tip displacement: η = √n q reads the same tip deflection as the HubAppendage output
    q = np.linspace(0.3, -0.2, hub.n_modes)
    x = np.concatenate([[0.0], q, np.zeros(hub.ndof)])
    tip = hub.outputs(x, 0.0)["tip_deflection"]
    assert modal.displacement_output(3, "y") @ (np.sqrt(n) * q) == pytest.approx(tip, rel=1e-13)
    # the root is clamped (the basis functions cancel there to roundoff)
    assert np.abs(modal.shapes[:, 0]).max() < 1e-14 * np.abs(modal.shapes).max()
    # translational modal momentum: e_i = ∫ρφ_i + m φ_i(l) by Gauss quadrature, × Σ t_j / √n
    modes = p.beam().modes(hub.n_modes)
    s, w = np.polynomial.legendre.leggauss(200)
    xi, w = 0.5 * p.length * (s + 1), 0.5 * p.length * w
    e = p.rho * w @ modes.evaluate(xi) + p.tip_mass * modes.evaluate([p.length])[0]
    expected_y = e if n == 1 else np.zeros_like(e)
    assert np.allclose(modal.participation[:, 1], expected_y, rtol=0, atol=1e-12 * np.abs(e).max())
    assert np.allclose(modal.participation[:, 5], np.sqrt(n) * hub.coupling, rtol=1e-15, atol=0)


def test_hub_appendage_matrices_errors():
    free = synthetic()
    with pytest.raises(ValueError, match="^modal: hybrid coordinates need a cantilevered"):
        hub_appendage_matrices(free, 1.0)
    cantilevered = synthetic(boundary="cantilevered")
    with pytest.raises(ValueError, match="^axis:"):
        hub_appendage_matrices(cantilevered, 1.0, axis=3)
    with pytest.raises(ValueError, match="^hub_inertia:"):
        hub_appendage_matrices(cantilevered, -1.0)
    with pytest.raises(ValueError, match="^stations:"):
        ModalModel.from_hub_appendage(hub_model(2), stations=[0.0, 2.0])
    M, _, _ = hub_appendage_matrices(cantilevered, 1.0, axis="x")
    assert M[0, 0] == 1.0 + cantilevered.rigid_mass[3, 3]
