"""Claims about the FE eigen-derivatives of :mod:`flexsat.analysis.fe_sensitivity`.

Finite-difference references use the five-point central difference
g' ≈ [−g(p+2h) + 8 g(p+h) − 8 g(p−h) + g(p−2h)] / 12h with h = 1e-3 |p|. Its truncation error is
h⁴ |g⁽⁵⁾|/30, ≈ 4e-12 relative for a power-law dependence g ~ p^k (|g⁽⁵⁾| ~ |g|/p⁵ up to k's
factorials), and its round-off is ≈ 1.5 ε_g |g|/h, with ε_g the relative accuracy of the
computed eigen-solution: ≈ 1e-13 for λ and ≈ 1e-11 for φ (shift-invert or dense pencil with a
Rayleigh-Ritz refinement), i.e. ≈ 1.5e-10 |λ|/|p| and 1.5e-8 ‖φ‖/|p|. The acceptance bound of
issue 23 is 1e-6 relative, here relative to max(|g'|, |g|/|p|): for a component whose
logarithmic sensitivity (p/g) ∂g/∂p is below 1 (a mode that barely sees the parameter, or does
not see it at all) the error is measured against |g|/|p|, the scale below which the
round-off bound of the difference would dominate any relative test.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from flexsat.analysis.fe_sensitivity import (
    LumpedInertia,
    LumpedMass,
    MemberProperty,
    RectangleSection,
    TubeSection,
    fe_modal_derivatives,
    fe_parameter_matrices,
    rectangle_section_derivatives,
    tube_section_derivatives,
)
from flexsat.analysis.sensitivity import modal_derivatives
from flexsat.cases.eps import eps
from flexsat.cases.tamu_grid import tamu_grid
from flexsat.input_checks import FieldError
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section

REL_STEP = 1e-3
ACCEPT = 1e-6  # issue 23: analytic gradient vs central differences, relative


def central(f, p: float):
    """Five-point central difference of f at p, step REL_STEP x |p| (see the module notes)."""
    h = REL_STEP * abs(p)
    return (-f(p + 2 * h) + 8 * f(p + h) - 8 * f(p - h) + f(p - 2 * h)) / (12.0 * h)


def within(analytic, fd, scale, what):
    """|analytic − fd| <= 1e-6 max(|fd|, scale), componentwise (norms per mode for shapes)."""
    err = np.abs(analytic - fd)
    bound = ACCEPT * np.maximum(np.abs(fd), scale)
    assert np.all(err <= bound), (what, err / np.maximum(np.abs(fd), scale))


def aligned(shapes, reference):
    """Mode shapes signed like ``reference`` (Assembly.modes signs each mode by its own rule)."""
    sign = np.sign(np.einsum("ij,ij->j", shapes, reference))
    return shapes * sign


def cantilever(E=70e9, rho=2700.0, D=0.05, t=0.004, tip=0.0, n_el=10, L=2.0, rect=None):
    """A clamped frame along x: a tube (D, t), or a rectangle ``rect`` = (b, h); a tip mass
    with unequal inertias about y and z splits the tube's pairs of bending modes."""
    s = Structure("cantilever")
    for i in range(n_el + 1):
        s.add_node(i, (L * i / n_el, 0.0, 0.0))
    mat = Material(E, rho)
    sec = Section.tube(D, t) if rect is None else Section.rectangle(*rect)
    for i in range(n_el):
        s.add_frame(i, i + 1, mat, sec)
    s.clamp(0)
    if tip:
        s.add_mass(n_el, tip, inertia=(0.01, 0.5, 0.05))
    return s


def free_frame(D=0.04, t=0.003, b=0.03, h=0.05, E=70e9, rho=2700.0, tip=3.0, J_tip=0.2):
    """A free-free planar-ish 3-D portal: tube legs, a rectangular beam, lumped masses."""
    s = Structure("free frame")
    pts = {1: (0, 0, 0), 2: (0, 0, 1.0), 3: (0.5, 0.1, 1.4), 4: (1.2, 0, 1.0), 5: (1.2, 0.3, 0)}
    for nid, x in pts.items():
        s.add_node(nid, x)
    mat = Material(E, rho)
    tube, rect = Section.tube(D, t), Section.rectangle(b, h)
    s.add_frame(1, 2, mat, tube)
    s.add_frame(2, 3, mat, rect)
    s.add_frame(3, 4, mat, rect)
    s.add_frame(4, 5, mat, tube)
    s.add_frame(2, 4, mat, tube)
    s.add_mass(5, tip, inertia=(J_tip, 0.5 * J_tip, 0.3 * J_tip))
    s.add_mass(3, 1.0)
    return s


# -- exact results ------------------------------------------------------------------------------
def test_eigenvalue_derivative_wrt_E_of_a_cantilever_is_omega_squared_over_E_exactly():
    # K is proportional to E (G = E / 2(1 + ν) follows it), M does not depend on E: λ = E c
    E = 70e9
    s = cantilever(E=E, rect=(0.03, 0.05))
    d = fe_modal_derivatives(s, [MemberProperty("E", tuple(range(10)))], range(6))
    np.testing.assert_allclose(d.eigenvalue_gradient[0], d.omegas**2 / E, rtol=1e-12)
    np.testing.assert_allclose(d.omega_gradient[0], d.omegas / (2 * E), rtol=1e-12)
    np.testing.assert_allclose(d.frequency_hz_gradient[0], d.frequencies_hz / (2 * E), rtol=1e-12)
    # the shapes do not change with a uniform stiffness scale
    assert np.abs(d.mode_gradient[0]).max() <= 1e-9 * np.abs(d.modes).max() / E


def test_eigenvalue_derivative_wrt_density_is_minus_omega_squared_over_rho_and_mass_is_rho_AL():
    rho, b, h, L = 2700.0, 0.03, 0.05, 2.0
    d = fe_modal_derivatives(
        cantilever(rho=rho, L=L, rect=(b, h)), [MemberProperty("rho", tuple(range(10)))], [0, 1, 4]
    )
    np.testing.assert_allclose(d.eigenvalue_gradient[0], -(d.omegas**2) / rho, rtol=1e-11)
    A = b * h
    assert d.mass == pytest.approx(rho * A * L, rel=1e-14)
    assert d.mass_gradient[0] == pytest.approx(A * L, rel=1e-14)


def test_bending_eigenvalues_scale_with_Iz_alone_and_axial_ones_ignore_it():
    # a 2-D beam: a bending mode's λ is proportional to E Iz, an axial mode's does not see Iz
    s = Structure("beam2d")
    for i in range(9):
        s.add_node(i, (0.25 * i, 0.0, 0.0))
    Iz = 2e-8
    for i in range(8):
        s.add_beam2d(i, i + 1, Material(70e9, 2700.0), Section(1e-4, 1e-8, Iz, 1e-8))
    s.clamp(0)
    d = fe_modal_derivatives(s, [MemberProperty("Iz", tuple(range(8)))], range(8))
    axial = np.abs(d.modes[s.assemble().index(8, "ux")]) > 1e-3 * np.abs(d.modes).max(axis=0)
    lam = d.eigenvalues
    assert axial.any() and (~axial).any()
    np.testing.assert_allclose(d.eigenvalue_gradient[0, ~axial], lam[~axial] / Iz, rtol=1e-9)
    assert np.all(np.abs(d.eigenvalue_gradient[0, axial]) <= 1e-9 * lam[axial] / Iz)


def test_fe_layer_agrees_with_the_dense_modal_derivatives():
    s = cantilever(tip=2.0)
    params = [TubeSection("thickness", tuple(range(10)), 0.05, 0.004), LumpedMass(10)]
    d = fe_modal_derivatives(s, params, [0, 2, 5])
    mats = fe_parameter_matrices(s, params)
    K, M = mats.assembly.K.toarray(), mats.assembly.M.toarray()
    ref = modal_derivatives(
        K,
        M,
        np.array([k.toarray() for k in mats.dK]),
        np.array([m.toarray() for m in mats.dM]),
        modes=[0, 2, 5],
    )
    scale = d.eigenvalues * np.array([[1 / 0.004], [1 / 2.0]])  # λ / p
    np.testing.assert_allclose(
        d.eigenvalue_gradient, ref.eigenvalue_gradient, atol=1e-9 * scale.max()
    )
    dphi = aligned(d.mode_gradient.reshape(-1, 3), np.tile(ref.modes, (2, 1)))
    np.testing.assert_allclose(
        np.abs(dphi), np.abs(ref.mode_gradient.reshape(-1, 3)), atol=1e-8 * np.abs(dphi).max()
    )


def test_section_formula_derivatives_match_the_section_formulas():
    for D, t in ((0.05, 0.004), (0.03, 0.012)):  # a thin and a thick tube
        g = tube_section_derivatives(D, t)
        fd_D = central(lambda x, t=t: np.array([(s := Section.tube(x, t)).A, s.Iy, s.Iz, s.J]), D)
        fd_t = central(lambda x, D=D: np.array([(s := Section.tube(D, x)).A, s.Iy, s.Iz, s.J]), t)
        np.testing.assert_allclose(g["outer_diameter"], fd_D, rtol=ACCEPT)
        np.testing.assert_allclose(g["thickness"], fd_t, rtol=ACCEPT)
    for b, h in ((0.03, 0.05), (0.05, 0.03), (0.04, 0.04), (0.01, 0.2)):
        g = rectangle_section_derivatives(b, h)
        fd_b = central(
            lambda x, h=h: np.array([(s := Section.rectangle(x, h)).A, s.Iy, s.Iz, s.J]), b
        )
        fd_h = central(
            lambda x, b=b: np.array([(s := Section.rectangle(b, x)).A, s.Iy, s.Iz, s.J]), h
        )
        if b == h:  # J is smooth through b = h; the central difference straddles the switch
            np.testing.assert_allclose(g["width"], fd_b, rtol=1e-5)
            np.testing.assert_allclose(g["height"], fd_h, rtol=1e-5)
        else:
            np.testing.assert_allclose(g["width"], fd_b, rtol=ACCEPT)
            np.testing.assert_allclose(g["height"], fd_h, rtol=ACCEPT)


# -- finite-difference checks -------------------------------------------------------------------
def _fd_check(build, params, values, modes, rigid=None, dense=False):
    """Every parameter's λ, φ and mass derivatives against central differences of ``build``.

    ``dense``: the reference modes come from scipy's dense ``eigh`` of the whole pencil (an
    independent solver; accurate to ε λ_max, so only for models without stiff axial dofs)
    instead of ``Assembly.modes``."""
    d = fe_modal_derivatives(build(**values), params, modes, rigid_body_modes=rigid)
    n_modes = max(modes) + 1
    for k, (name, p0) in enumerate(values.items()):

        def solve(p, part, name=name):
            s = build(**{**values, name: p})
            if part == "mass":
                return s.structural_mass()
            if dense:
                a = s.assemble()
                lam, X = sla.eigh(a.K.toarray(), a.M.toarray(), subset_by_index=[0, n_modes - 1])
            else:
                fe = s.assemble().modes(n_modes, rigid_body_modes=rigid)
                lam, X = fe.omegas**2, fe.shapes
            if part == "eigenvalues":
                return lam[modes]
            return aligned(X[:, modes], d.modes)

        lam_fd = central(lambda p: solve(p, "eigenvalues"), p0)
        within(d.eigenvalue_gradient[k], lam_fd, d.eigenvalues / abs(p0), (name, "λ"))
        phi_fd = central(lambda p: solve(p, "modes"), p0)
        within(
            np.linalg.norm(d.mode_gradient[k] - phi_fd, axis=0) + np.linalg.norm(phi_fd, axis=0),
            np.linalg.norm(phi_fd, axis=0),
            np.linalg.norm(d.modes, axis=0) / abs(p0),
            (name, "φ"),
        )
        mass_fd = central(lambda p: solve(p, "mass"), p0)
        within(d.mass_gradient[k], mass_fd, d.mass / abs(p0), (name, "mass"))
    return d


def test_cantilever_with_tip_mass_matches_central_differences():
    values = dict(E=70e9, rho=2700.0, D=0.05, t=0.004, tip=2.0)
    all_el = tuple(range(10))
    params = [
        MemberProperty("E", all_el),
        MemberProperty("rho", all_el),
        TubeSection("outer_diameter", all_el, 0.05, 0.004),
        TubeSection("thickness", all_el, 0.05, 0.004),
        LumpedMass(10),
    ]
    _fd_check(cantilever, params, values, [0, 2, 3, 6])


def test_free_free_frame_elastic_modes_match_central_differences():
    values = dict(D=0.04, t=0.003, b=0.03, h=0.05, tip=3.0)
    tubes, rects = (0, 3, 4), (1, 2)
    params = [
        TubeSection("outer_diameter", tubes, 0.04, 0.003),
        TubeSection("thickness", tubes, 0.04, 0.003),
        RectangleSection("width", rects, 0.03, 0.05),
        RectangleSection("height", rects, 0.03, 0.05),
        LumpedMass(5),
    ]
    d = _fd_check(free_frame, params, values, [6, 7, 8, 9], rigid=6, dense=True)
    assert np.all(d.omegas > 0)
    # J_tip scales the tip inertia (J, J/2, 0.3 J): ∂/∂J_tip = ∂/∂Ixx + ½ ∂/∂Iyy + 0.3 ∂/∂Izz
    inertia = fe_modal_derivatives(
        free_frame(),
        [LumpedInertia(5, "x"), LumpedInertia(5, "y"), LumpedInertia(5, "z")],
        [6, 7, 8, 9],
        rigid_body_modes=6,
    )
    combined = inertia.eigenvalue_gradient.T @ np.array([1.0, 0.5, 0.3])

    def lam(J):
        return free_frame(J_tip=J).assemble().modes(10, rigid_body_modes=6).omegas[6:10] ** 2

    within(combined, central(lam, 0.2), inertia.eigenvalues / 0.2, "J_tip")


def test_tamu_grid_with_gravity_preloads_matches_central_differences():
    # EI and GJ of every member; the gravity tensions do not depend on them (held fixed)
    base = tamu_grid()

    def build(EI, GJ, motor_mass):
        return tamu_grid(EI=EI, GJ=GJ, motor_mass=motor_mass).structure(gravity=True)

    all_el = tuple(range(build(base.EI, base.GJ, base.motor_mass).n_elements))
    params = [MemberProperty("EI", all_el), MemberProperty("GJ", all_el)]
    values = dict(EI=base.EI, GJ=base.GJ)
    _fd_check(lambda **v: build(**v, motor_mass=base.motor_mass), params, values, [0, 1, 2, 4])
    # motor mass (0.5 kg, a design point with motors): one parameter on all motor nodes = the
    # sum of the per-node gradients (the tensions change with it, so gravity is off here)
    m0 = 0.5
    s = tamu_grid(motor_mass=m0).structure(gravity=False)
    d = fe_modal_derivatives(s, [LumpedMass(n) for n in base.motor_nodes], [0, 1, 2])

    def lam(m):
        return tamu_grid(motor_mass=m).structure(gravity=False).assemble().modes(3).omegas ** 2

    assert np.all(d.eigenvalue_gradient < 0)  # added mass lowers every frequency
    within(d.eigenvalue_gradient.sum(axis=0), central(lam, m0), d.eigenvalues / m0, "motor_mass")


def _eps_like(D, t, antenna_mass=20.0):
    """The EPS truss and antennas (nodes and members of ``eps()``), tube section (D, t), free."""
    ref = eps().structure()
    s = Structure("EPS-like")
    for nid, x in zip(ref.node_ids, ref.coordinates):
        s.add_node(int(nid), x)
    c = ref.element(0)["properties"]
    mat = Material(E=c["E"], rho=c["rho"], G=c["G"])
    for e in range(ref.n_elements):
        s.add_frame(*ref.element(e)["nodes"], mat, Section.tube(D, t))
    s.add_mass(int(ref.node_ids[-1]), antenna_mass)
    return s


def test_eps_like_truss_tube_wall_and_diameter_match_central_differences():
    case = eps()
    D, t = case.tube_outer_diameter, case.tube_wall
    n = _eps_like(D, t).n_elements
    params = [
        TubeSection("outer_diameter", tuple(range(n)), D, t),
        TubeSection("thickness", tuple(range(n)), D, t),
    ]
    _fd_check(_eps_like, params, dict(D=D, t=t), [6, 7, 8, 9], rigid=6)


# -- refusals -------------------------------------------------------------------------------------
def test_rigid_body_modes_are_refused_by_name():
    with pytest.raises(FieldError, match="modes.*rigid-body"):
        fe_modal_derivatives(free_frame(), [LumpedMass(5)], [0, 6], rigid_body_modes=6)


def test_repeated_eigenvalues_are_refused_by_name():
    # a square tube cantilever bends alike in both planes: modes 0 and 1 coincide
    with pytest.raises(FieldError, match="modes.*repeated"):
        fe_modal_derivatives(cantilever(), [MemberProperty("E", (0,))], [0])


@pytest.mark.parametrize(
    "params, field",
    [
        ([MemberProperty("EI", (0,))], "quantity"),
        ([MemberProperty("A", (99,))], "element"),
        ([MemberProperty("A", ())], "elements"),
        ([MemberProperty("A", (0, 0))], "elements"),
        ([TubeSection("thickness", (0,), 0.06, 0.004)], "TubeSection"),
        ([TubeSection("wall", (0,), 0.05, 0.004)], "dimension"),
        ([LumpedMass(0)], "LumpedMass"),  # node 0 is clamped
        ([LumpedInertia(10, "w")], "axis"),
        (["A"], "parameters"),
        ([], "parameters"),
    ],
)
def test_bad_parameters_are_refused_by_name(params, field):
    with pytest.raises(ValueError, match=field):
        fe_parameter_matrices(cantilever(tip=1.0), params)


def test_bad_mode_numbers_are_refused_by_name():
    for modes in ([], [-1], [1.5], [2, 2], [10_000]):
        with pytest.raises(FieldError, match="modes"):
            fe_modal_derivatives(cantilever(tip=1.0), [LumpedMass(10)], modes)


def test_a_section_direction_is_the_sum_of_its_single_property_derivatives():
    # the element matrices are jointly affine in (A, Iy, Iz, J): one directional derivative
    # equals the combination of the four single ones, to round-off
    s = cantilever(tip=1.0)
    group = tuple(range(10))
    c = {"A": 0.3, "Iy": 2e-3, "Iz": -1e-3, "J": 5e-4}
    dK, dM, dm = s.property_derivative(c, group)
    singles = [s.property_derivative(q, group) for q in c]
    K_sum = sum(w * k for w, (k, _, _) in zip(c.values(), singles))
    M_sum = sum(w * m for w, (_, m, _) in zip(c.values(), singles))
    assert abs(dK - K_sum).max() <= 1e-12 * abs(K_sum).max()
    assert abs(dM - M_sum).max() <= 1e-12 * abs(M_sum).max()
    assert dm == pytest.approx(sum(w * d for w, (_, _, d) in zip(c.values(), singles)), rel=1e-13)


def test_mixing_section_and_material_properties_or_a_tied_G_is_refused_by_name():
    s = cantilever()
    with pytest.raises(FieldError, match="quantity.*affine"):
        s.property_derivative({"A": 1.0, "E": 1.0}, (0,))  # E A is bilinear
    with pytest.raises(FieldError, match="quantity.*follows E"):
        s.property_derivative("G", (0,))  # G = E / 2(1 + ν) here
    with pytest.raises(FieldError, match="direction"):
        s.property_derivative({}, (0,))
    with pytest.raises(ValueError, match="direction"):
        s.property_derivative({"A": float("nan")}, (0,))


def test_rigid_body_motions_are_null_vectors_of_every_stiffness_derivative():
    # why the rigid modes of a free structure stay at ω = 0 for every parameter
    params = [
        TubeSection("outer_diameter", (0, 3, 4), 0.04, 0.003),
        RectangleSection("height", (1, 2), 0.03, 0.05),
        MemberProperty("E", (0, 1, 2, 3, 4)),
    ]
    mats = fe_parameter_matrices(free_frame(), params)
    R = mats.assembly.rigid_body_vectors()
    for dK in mats.dK:
        assert np.abs(dK @ R).max() <= 1e-12 * abs(dK).max() * np.abs(R).max()


def _offset_and_linked(tip=0.4, linked=0.3):
    """A cantilever with a tip body 5 cm off its node (rigid offset) and a mass on a node tied
    to the tip by a rigid link: ∂M of each is Tᵀ diag(I₃, 0) T, carried by the link's G."""
    s = cantilever(n_el=4, rect=(0.03, 0.02))
    s.add_mass(4, tip, inertia=(1e-4, 2e-4, 3e-4), offset=(0.0, 0.03, 0.05))
    s.add_node(9, (2.0, 0.1, 0.12))
    s.add_rigid_link(4, (9,))
    s.add_mass(9, linked)
    return s


def test_offset_and_rigidly_linked_masses_match_central_differences():
    params = [LumpedMass(4, offset=(0.0, 0.03, 0.05)), LumpedMass(9)]
    _fd_check(_offset_and_linked, params, dict(tip=0.4, linked=0.3), [0, 1, 2, 3])
    # the offset matters: the node-only derivative (no offset) is a different matrix
    bare = fe_parameter_matrices(_offset_and_linked(), [LumpedMass(4)]).dM[0]
    moved = fe_parameter_matrices(_offset_and_linked(), params[:1]).dM[0]
    assert abs(bare - moved).max() > 1e-3
