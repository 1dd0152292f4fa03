"""The compiled closed-loop kernel (flexsat.sim.kernels) equals a plain-numpy loop of the same
sampled-data equations, feature by feature, and its noise is reproducible per case.

Small random systems keep numba's compile (cached after the first run) and the loops cheap.
Tolerances: the kernel sums in a different order than numpy's matrix products, so the two agree
to round-off of a stable loop over a few dozen samples: 1e-12 relative (~ n · eps · steps with
margin); quantized channels agree exactly unless a value sits within round-off of a rounding
boundary, which random data avoids.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm

from flexsat.sim.integrators import phi_products
from flexsat.sim.kernels import (
    ARGUMENTS,
    RECORDS,
    Loop,
    allocate_records,
    closed_loop,
    closed_loop_parallel,
)
from flexsat.sim.sensors import least_squares_derivative_weights

N_SLOTS = 4


def make_problem(
    seed=0,
    n_cases=3,
    n=4,
    m=2,
    p=3,
    nk=2,
    n_t=40,
    dt=0.05,
    substeps=2,
    force=True,
    impulses=True,
    quantum=True,
    noise=True,
    bias=True,
    saturation=True,
    fir=True,
    law_state=True,
    k0=True,
    actuator=True,
    disturbance=True,
    per_case=True,
    scheduled=True,
):
    """Random stable plant (damped oscillators, coupled) and law; every feature switchable."""
    rng = np.random.default_rng(seed)
    Cp = n_cases if per_case else 1
    h = dt / substeps
    E = np.empty((Cp, n, n))
    P1u = np.empty((Cp, n, m))
    P1f = np.empty((Cp if force else 0, n))
    P2f = np.empty((Cp if force else 0, n))
    for c in range(Cp):
        A = rng.normal(size=(n, n)) - 3.0 * np.eye(n)
        B = rng.normal(size=(n, m))
        bf = rng.normal(size=(n, 1))
        Ec, P1, P2 = phi_products(A, h, np.hstack([B, bf]), 1)
        E[c], P1u[c] = Ec, P1[:, :m]
        if force:
            P1f[c], P2f[c] = P1[:, m], P2[:, 0]
    Cr = rng.normal(size=(Cp if force else 0, n))
    fric = np.column_stack(
        [rng.uniform(0.2, 0.5, Cp), rng.uniform(0.0, 0.2, Cp), rng.uniform(0.05, 0.2, Cp)]
    )
    imp_k = np.array([0, 5, 5, 17] if impulses else [], dtype=np.int64)
    imp_dx = rng.normal(size=(imp_k.size, n_cases, n))
    Cm = rng.normal(size=(Cp, p, n))
    Dm = rng.normal(size=(Cp, p, m)) * 0.3
    Dmf = rng.normal(size=(Cp, p)) * 0.3
    sensor = np.zeros((Cp, p, 4))
    sensor[:, :, 0] = 0.01 * quantum
    sensor[:, :, 1] = 0.02 * noise
    sensor[:, :, 2] = rng.normal(size=(Cp, p)) * 0.05 * bias
    sensor[:, :, 3] = 2.0 if saturation else np.inf
    sensor_slot = np.array([i % N_SLOTS if noise else -1 for i in range(p)], dtype=np.int64)
    fir_w = least_squares_derivative_weights(5, 1, dt) if fir else np.zeros(0)
    T = n_t if scheduled else 1
    nkk = nk if law_state else 0
    Ak = 0.5 * rng.normal(size=(T, n_cases, nkk, nkk)) / max(nkk, 1)
    Bk = rng.normal(size=(T, n_cases, nkk, p))
    Ck = 0.3 * rng.normal(size=(T, n_cases, m, nkk))
    Dk = -0.5 * rng.uniform(size=(T, n_cases, m, p))
    y_ref = rng.normal(size=(n_t, n_cases, p))
    u_ff = rng.normal(size=(n_t, n_cases, m)) * 0.2
    K0 = rng.normal(size=(n_cases if (k0 and law_state) else 0, nkk, p))
    act = np.empty((Cp, m, 2))
    act[:, :, 0] = 0.8 if actuator else np.inf
    act[:, :, 1] = rng.uniform(0.9, 1.1, (Cp, m)) if actuator else 1.0
    dist_std = np.full((Cp, m), 0.1 if disturbance else 0.0)
    dist_slot = np.array(
        [(p + i) % N_SLOTS if disturbance else -1 for i in range(m)], dtype=np.int64
    )
    noise_arr = np.empty((n_cases, n_t, N_SLOTS))
    for c in range(n_cases):  # one stream per case seed
        noise_arr[c] = np.random.default_rng(100 + c).standard_normal((n_t, N_SLOTS))
    x0 = rng.normal(size=(n_cases, n))
    # recorded output rows and a symmetric energy matrix (drawn last: the draws above keep
    # their values)
    Co, Do = rng.normal(size=(Cp, 2, n)), rng.normal(size=(Cp, 2, m))
    Dof = rng.normal(size=(Cp, 2))
    R = rng.normal(size=(Cp, n, n))
    Q = R @ np.swapaxes(R, 1, 2)
    return dict(
        Co=Co,
        Do=Do,
        Dof=Dof,
        Q=Q,
        x0=x0,
        E=E,
        block_diagonal=False,
        P1u=P1u,
        P1f=P1f,
        P2f=P2f,
        Cr=Cr,
        fric=fric,
        substeps=substeps,
        imp_k=imp_k,
        imp_dx=imp_dx,
        Cm=Cm,
        Dm=Dm,
        Dmf=Dmf,
        sensor=sensor,
        sensor_slot=sensor_slot,
        fir_src=0 if fir else -1,
        fir_dst=1,
        fir_w=fir_w,
        Ak=Ak,
        Bk=Bk,
        Ck=Ck,
        Dk=Dk,
        y_ref=y_ref,
        u_ff=u_ff,
        K0=K0,
        act=act,
        dist_std=dist_std,
        dist_slot=dist_slot,
        noise=noise_arr,
        bound=1e12,
    )


def run_kernel(prob, parallel=False, record_states=True):
    n_t, (nc, n) = prob["y_ref"].shape[0], prob["x0"].shape
    m, p = prob["P1u"].shape[2], prob["Cm"].shape[1]
    rec = allocate_records(n_t, nc, n, m, p, record_states, prob["Co"].shape[1], True)
    fn = closed_loop_parallel if parallel else closed_loop
    fn(Loop(*(prob[k] for k in ARGUMENTS)), rec)
    return dict(zip(RECORDS, rec))


def reference_loop(prob):
    """The same loop in plain numpy, one case at a time (module docstring of kernels.py)."""
    P = prob
    n_t, nc, n = P["y_ref"].shape[0], *P["x0"].shape
    m, p = P["P1u"].shape[2], P["Cm"].shape[1]
    nk = P["Ak"].shape[2]
    has_force = P["P1f"].shape[0] > 0

    def pick(a, c):
        return a[0] if a.shape[0] == 1 else a[c]

    def law(a, k, c):
        return pick(pick(a, k), c)

    out = {
        k: np.full(s, np.nan)
        for k, s in (
            ("X", (nc, n_t, n)),
            ("Y", (nc, n_t, p)),
            ("Ucmd", (nc, n_t, m)),
            ("U", (nc, n_t, m)),
            ("D", (nc, n_t, m)),
            ("F", (nc, n_t)),
            ("O", (nc, n_t, P["Co"].shape[1])),
            ("En", (nc, n_t)),
        )
    }
    out["stop"] = np.full(nc, -1)
    for c in range(nc):
        if has_force:
            c1, c2, eps = pick(P["fric"], c)
            cr = pick(P["Cr"], c)

            def N(x, cr=cr, c1=c1, c2=c2, eps=eps):
                r = cr @ x
                return -c1 * np.tanh(r / eps) - c2 * r
        else:

            def N(x):
                return 0.0

        E, P1u = pick(P["E"], c), pick(P["P1u"], c)
        Cm, Dm, Dmf, sens = (pick(P[k], c) for k in ("Cm", "Dm", "Dmf", "sensor"))
        act, dstd = pick(P["act"], c), pick(P["dist_std"], c)
        x = P["x0"][c].copy()
        w = np.zeros(m)
        xi = np.zeros(nk)
        hist = None
        for k in range(n_t):
            for kk, dx in zip(P["imp_k"], P["imp_dx"]):
                if kk == k:
                    x = x + pick(dx, c)
            f = N(x)
            y = Cm @ x + Dm @ w + Dmf * f + sens[:, 2]
            slot = P["sensor_slot"]
            y = y + np.where(slot >= 0, sens[:, 1] * P["noise"][c, k, slot], 0.0)
            q = sens[:, 0]
            y = np.where(q > 0, q * np.round(y / np.where(q > 0, q, 1.0)), y)
            y = np.clip(y, -sens[:, 3], sens[:, 3])
            if P["fir_src"] >= 0:
                src = y[P["fir_src"]]
                hist = np.full(P["fir_w"].size, src) if hist is None else np.append(hist[1:], src)
                y[P["fir_dst"]] = P["fir_w"] @ hist
            e = y - P["y_ref"][k, 0 if P["y_ref"].shape[1] == 1 else c]
            if k == 0 and P["K0"].shape[0] > 0:
                xi = pick(P["K0"], c) @ e
            u_ff = P["u_ff"][k, 0 if P["u_ff"].shape[1] == 1 else c]
            u_cmd = u_ff + law(P["Ck"], k, c) @ xi + law(P["Dk"], k, c) @ e
            xi = law(P["Ak"], k, c) @ xi + law(P["Bk"], k, c) @ e
            out["X"][c, k], out["Y"][c, k], out["Ucmd"][c, k], out["F"][c, k] = x, y, u_cmd, f
            # the recorded outputs (no sensor effects) and the energy ½ xᵀ Q x
            out["O"][c, k] = pick(P["Co"], c) @ x + pick(P["Do"], c) @ w + pick(P["Dof"], c) * f
            out["En"][c, k] = 0.5 * x @ pick(P["Q"], c) @ x
            if not (np.all(np.abs(x) <= P["bound"]) and np.all(np.abs(u_cmd) <= P["bound"])):
                out["stop"][c] = k
                break
            u = act[:, 1] * np.clip(u_cmd, -act[:, 0], act[:, 0])
            ds = P["dist_slot"]
            d = np.where(ds >= 0, dstd * P["noise"][c, k, ds], 0.0)
            out["U"][c, k], out["D"][c, k] = u, d
            w = u + d
            if k == n_t - 1:
                break
            for _ in range(P["substeps"]):
                f0 = N(x)
                a = E @ x + P1u @ w + (pick(P["P1f"], c) * f0 if has_force else 0.0)
                x = a + (pick(P["P2f"], c) * (N(a) - f0) if has_force else 0.0)
    return out


def assert_matches(prob, rtol=1e-12):
    got, ref = run_kernel(prob), reference_loop(prob)
    np.testing.assert_array_equal(got["stop"], ref["stop"])
    for key in ("X", "Y", "Ucmd", "U", "D", "F", "O", "En"):
        scale = max(np.nanmax(np.abs(ref[key])), 1e-300)
        valid = ~np.isnan(ref[key])
        np.testing.assert_allclose(
            got[key][valid], ref[key][valid], rtol=0, atol=rtol * scale, err_msg=key
        )
    return got, ref


def test_every_feature_on_matches_numpy_reference():
    got, _ = assert_matches(make_problem())
    assert (got["stop"] == -1).all()


FEATURES = (
    "force",
    "impulses",
    "quantum",
    "noise",
    "bias",
    "saturation",
    "fir",
    "law_state",
    "k0",
    "actuator",
    "disturbance",
    "per_case",
    "scheduled",
)


@pytest.mark.parametrize("feature", FEATURES)
def test_each_feature_alone_matches_numpy_reference(feature):
    off = {f: False for f in FEATURES}
    off[feature] = True
    if feature == "k0":
        off["law_state"] = True
    got, ref = assert_matches(make_problem(seed=1, **off))
    # the feature changes the result (it is not silently ignored)
    base = run_kernel(make_problem(seed=1, **{f: False for f in FEATURES}))
    if feature not in ("per_case",):
        assert not np.allclose(got["Ucmd"], base["Ucmd"], rtol=1e-9, atol=0), feature


def test_block_diagonal_propagation_equals_dense_block_matrix():
    prob = make_problem(force=False, per_case=False)
    E = prob["E"][0]
    n = E.shape[0]
    Eb = np.zeros_like(E)
    rows = np.empty((n, 2))
    for i in range(0, n, 2):
        Eb[i : i + 2, i : i + 2] = rows[i : i + 2] = E[i : i + 2, i : i + 2]
    a = run_kernel(dict(prob, E=Eb[None]))
    b = run_kernel(dict(prob, E=rows[None], block_diagonal=True))
    for key in ("X", "Y", "Ucmd"):
        np.testing.assert_allclose(b[key], a[key], rtol=1e-13, atol=1e-13, err_msg=key)


def test_exact_zoh_step_of_linear_plant():
    # no law, no sensors: x_{k+1} = e^{A dt} x_k + ∫ e^{As} ds B u_ff[k] (exact ZOH)
    rng = np.random.default_rng(3)
    n, m, dt, n_t = 3, 1, 0.1, 6
    A = rng.normal(size=(n, n)) - np.eye(n)
    B = rng.normal(size=(n, m))
    prob = make_problem(
        n_cases=1, n=n, m=m, p=1, n_t=n_t, dt=dt, substeps=3, **{f: False for f in FEATURES}
    )
    E, P1, _ = phi_products(A, dt / 3, B)
    prob.update(E=E[None], P1u=P1[None], Dk=np.zeros((1, 1, m, 1)))
    got = run_kernel(prob)
    Ed, Pd, _ = phi_products(A, dt, B)
    x = prob["x0"][0]
    for k in range(n_t):
        np.testing.assert_allclose(got["X"][0, k], x, rtol=1e-12, atol=1e-14)
        x = Ed @ x + Pd @ prob["u_ff"][k, 0]
    assert np.allclose(expm(A * dt), Ed, rtol=1e-13)


def test_divergence_stops_at_first_bad_sample():
    prob = make_problem(seed=2, n_cases=2, **{f: False for f in FEATURES})
    prob["Dk"] = prob["Dk"].copy()
    prob["bound"] = 1e3
    prob["u_ff"] = prob["u_ff"].copy()
    prob["u_ff"][7, 1, 0] = 1e4  # case 1: a command beyond the bound at sample 7
    prob["x0"] = prob["x0"].copy()
    prob["x0"][0, 0] = np.nan  # case 0: a non-finite state at once
    got, ref = assert_matches(prob)
    assert got["stop"].tolist() == [0, 7]


def test_parallel_is_bit_identical_to_serial():
    prob = make_problem(seed=4, n_cases=9)
    a, b = run_kernel(prob), run_kernel(prob, parallel=True)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_noise_reproducible_per_case():
    # a case run alone with its own stream reproduces its batch result bit for bit
    prob = make_problem(seed=5, n_cases=4, per_case=False)
    batch = run_kernel(prob, parallel=True)
    c = 2
    alone = {
        k: (
            v[:, c : c + 1]
            if k in ("Ak", "Bk", "Ck", "Dk", "y_ref", "u_ff", "imp_dx")
            else v[c : c + 1]
            if k in ("x0", "K0", "noise")
            else v
        )
        for k, v in prob.items()
    }
    single = run_kernel(alone)
    for key in ("X", "Y", "Ucmd", "U", "D", "F"):
        np.testing.assert_array_equal(single[key][0], batch[key][c], err_msg=key)
