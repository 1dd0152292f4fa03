"""Issue-23 benchmark: cost of analytic gradients relative to their objective.

For each kind of gradient, wall time (best of N) of the objective alone and of objective plus
gradient, and their ratio (target of issue 23: <= 3 for adjoint gradients); beside it the ratio
a central finite difference would cost (2P objective evaluations plus one).

* LQ cost J = tr(S X0), continuous and discrete: objective = the Riccati solve, K and J;
  gradient = :func:`flexsat.analysis.riccati_sensitivity.lq_cost_gradient` (one extra Lyapunov
  solve gives ∂J/∂A, ∂B, ∂Q, ∂R at once: all n² + nm + ... entries). Modal model of
  ``bench_lqr.py`` (a rigid mode plus lightly damped modes, 2 inputs, Q = R = X0 = I). The
  gradient's time includes its input checks (symmetry and definiteness of Q, R, X0), which the
  bare objective skips: the ratio is an upper bound.
* H2 norm: objective = the Hurwitz check and one Gramian; gradient = :func:`h2_norm_gradient`
  (the second Gramian is the adjoint).
* FE eigen-derivatives (not an adjoint): objective = assemble + lowest modes of the EPS truss
  (``flexsat.cases.eps``, 570 dofs, free); gradient = :func:`fe_modal_derivatives` for 4 elastic
  modes and P = 2 (tube diameter and wall of all members) or P = 8 (A, Iy, Iz, J of two member
  groups): one factorisation per mode, P right-hand sides.
* Simulation metric, adjoint (process CPU, not wall): objective = the discrete LQR gain of the
  ZOH model, the loop run on the engine (:func:`flexsat.design.sampled_loop.sampled_lq_loop`)
  and the metric; gradient = :func:`flexsat.design.sampled_loop.loop_gradient` (backward sweep,
  one Stein solve, one Fréchet derivative of the block exponential: ∂J/∂A, ∂B, ∂Q_d, ∂R_d, ∂x₀,
  ∂r at once). Plants: the hub-boom slew of ``HubBoomCodesign`` (8 states, 50 Hz, 150 steps)
  and a 20-mode modal plant (40 states, 100 Hz, 1000 steps). Metrics: residual energy at T,
  and all four (energy, pointing, smooth peak, soft settling) from one run.

    PYTHONPATH=src .venv/bin/python benchmarks/bench_sensitivities.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.linalg as sla

from flexsat.analysis.fe_sensitivity import MemberProperty, TubeSection, fe_modal_derivatives
from flexsat.analysis.riccati_sensitivity import h2_norm_gradient, lq_cost_gradient
from flexsat.analysis.sampled_sensitivity import (
    smooth_peak,
    soft_settling,
    terminal_energy,
    terminal_error,
)
from flexsat.cases.eps import eps
from flexsat.design.reference_problems import HubBoomCodesign
from flexsat.design.sampled_loop import loop_gradient, sampled_lq_loop


def modal_model(n_states: int, zeta: float = 0.005, n_inputs: int = 2, seed: int = 0):
    m = n_states // 2
    w = np.concatenate([[0.0], np.geomspace(0.1, 100.0, m - 1)])
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-np.diag(w**2), -np.diag(2 * zeta * w)]])
    B = np.vstack(
        [np.zeros((m, n_inputs)), np.random.default_rng(seed).standard_normal((m, n_inputs))]
    )
    return A, B


def best_pair(repeats: int, objective, gradient) -> tuple[float, float]:
    """Best-of-N wall times of ``objective`` and ``gradient``, interleaved (one of each per
    repeat, so a load change on the shared machine hits both alike)."""
    times = []
    for _ in range(repeats):
        pair = []
        for fn in (objective, gradient):
            t0 = time.perf_counter()
            fn()
            pair.append(time.perf_counter() - t0)
        times.append(pair)
    t = np.array(times)
    return float(t[:, 0].min()), float(t[:, 1].min())


def best_pair_cpu(repeats: int, objective, gradient) -> tuple[float, float]:
    """As :func:`best_pair` in process CPU time (time.process_time: the machine is shared)."""
    times = []
    for _ in range(repeats):
        pair = []
        for fn in (objective, gradient):
            t0 = time.process_time()
            fn()
            pair.append(time.process_time() - t0)
        times.append(pair)
    t = np.array(times)
    return float(t[:, 0].min()), float(t[:, 1].min())


def hub_boom_plant():
    """The modal plant (A, B, Q, x_f) of HubBoomCodesign at its start design and its sampling."""
    hb = HubBoomCodesign(maneuver=True)
    m = hb.modal_plant(np.array(hb.start))
    h = 1.0 / hb.control_rate
    steps = int(round(hb.maneuver_time * hb.control_rate))
    return m.A, m.B, m.Q * h, np.array([[hb.control_weight * h]]), h, steps, m.C[0], m.x0


def simulation_rows(repeats):
    """Adjoint gradients of metrics of the engine-run sampled LQ loop (module docstring)."""
    A, B, Qd, Rd, h, steps, c, xf = hub_boom_plant()
    Am, Bm = modal_model(40, zeta=0.01, n_inputs=1)
    nm = 20
    cm = np.concatenate([np.ones(nm), np.zeros(nm)]) / np.sqrt(nm)
    cases = [
        ("hub-boom slew, n = 8, N = 150", A, B, Qd, Rd, h, steps, np.zeros(A.shape[0]), xf, c),
        (
            "modal plant, n = 40, N = 1000",
            Am,
            Bm,
            0.01 * np.eye(40),
            0.01 * np.eye(1),
            0.01,
            1000,
            np.zeros(40),
            np.concatenate([np.full(nm, 0.1), np.zeros(nm)]),
            cm,
        ),
    ]
    rows = []
    for name, A, B, Q, R, h, steps, x0, r, c in cases:
        n = A.shape[0]
        W = np.eye(n)
        target = float(c @ r)

        def metrics(loop, c=c, target=target, W=W, h=h):
            X, U = loop.X, loop.U
            return [
                terminal_energy(X, U, W),
                terminal_error(X, U, c, target),
                smooth_peak(X, U, 16),
                soft_settling(X, U, c, target, 0.01 * max(abs(target), 1e-3), 0.2, h),
            ]

        def run(A=A, B=B, Q=Q, R=R, h=h, steps=steps, x0=x0, r=r):
            return sampled_lq_loop(A, B, Q, R, h, steps, x0, r)

        P = 2 * n * n + n * B.shape[1] + B.shape[1] ** 2 + 2 * n
        for label, k in (("energy at T", 1), ("all four metrics", 4)):

            def objective(k=k, run=run, metrics=metrics):
                loop = run()
                return [mv.value for mv in metrics(loop)[:k]]

            def gradient(k=k, run=run, metrics=metrics):
                loop = run()
                return [loop_gradient(loop, mv) for mv in metrics(loop)[:k]]

            t_obj, t_grad = best_pair_cpu(repeats, objective, gradient)
            rows.append((f"simulation metric, adjoint ({label})", name, P, t_obj, t_grad))
    return rows


def lq_rows(sizes, repeats):
    rows = []
    for n in sizes:
        A, B = modal_model(n)
        Q, R, X0 = np.eye(n), np.eye(B.shape[1]), np.eye(n)
        for discrete in (False, True):
            Ad, Bd = (sla.expm(0.01 * A), 0.01 * B) if discrete else (A, B)

            def objective(Ad=Ad, Bd=Bd, discrete=discrete):
                if discrete:
                    S = sla.solve_discrete_are(Ad, Bd, Q, R)
                    np.linalg.solve(R + Bd.T @ S @ Bd, Bd.T @ S @ Ad)
                else:
                    S = sla.solve_continuous_are(Ad, Bd, Q, R)
                    np.linalg.solve(R, Bd.T @ S)
                return float(np.sum(S * X0))

            t_obj, t_grad = best_pair(
                repeats,
                objective,
                lambda Ad=Ad, Bd=Bd, d=discrete: lq_cost_gradient(Ad, Bd, Q, R, X0, discrete=d),
            )
            P = n * n + n * B.shape[1]  # entries of A and B alone
            kind = "LQ cost, discrete" if discrete else "LQ cost, continuous"
            rows.append((kind, f"n = {n}", P, t_obj, t_grad))
    return rows


def h2_rows(sizes, repeats):
    rows = []
    for n in sizes:
        A, B = modal_model(n)
        A = A - 0.01 * np.eye(n)  # Hurwitz (the rigid mode is given a little damping)
        C = np.hstack([np.eye(n // 2), np.zeros((n // 2, n // 2))])

        def objective(A=A, B=B, C=C):
            # the Hurwitz check any H2 evaluation needs (an unstable plant has no H2 norm)
            assert np.linalg.eigvals(A).real.max() < 0
            Lc = sla.solve_continuous_lyapunov(A, -B @ B.T)
            return np.sqrt(np.trace(C @ Lc @ C.T))

        t_obj, t_grad = best_pair(
            repeats, objective, lambda A=A, B=B, C=C: h2_norm_gradient(A, B, C)
        )
        rows.append(("H2 norm", f"n = {n}", n * n + n * B.shape[1], t_obj, t_grad))
    return rows


def fe_rows(repeats):
    case = eps()
    s = case.structure()
    n_el = s.n_elements
    D, t = case.tube_outer_diameter, case.tube_wall
    labels = [s.element(e)["label"] for e in range(n_el)]
    truss = tuple(e for e in range(n_el) if labels[e] == "truss")
    antenna = tuple(e for e in range(n_el) if labels[e].startswith("antenna"))
    modes = [6, 7, 8, 9]
    sets = {
        "P = 2 (tube D, t)": [
            TubeSection("outer_diameter", tuple(range(n_el)), D, t),
            TubeSection("thickness", tuple(range(n_el)), D, t),
        ],
        "P = 8 (A, Iy, Iz, J x 2 groups)": [
            MemberProperty(q, g) for g in (truss, antenna) for q in ("A", "Iy", "Iz", "J")
        ],
    }

    def objective():
        return s.assemble().modes(max(modes) + 2, rigid_body_modes=6).omegas

    rows = []
    for name, params in sets.items():
        t_obj, t_grad = best_pair(
            repeats,
            objective,
            lambda p=params: fe_modal_derivatives(s, p, modes, rigid_body_modes=6),
        )
        rows.append(("FE modes (EPS, 4 modes, Nelson)", name, len(params), t_obj, t_grad))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--sizes", default="20,50,100")
    parser.add_argument("--only-simulation", action="store_true")
    args = parser.parse_args()
    sizes = [int(x) for x in args.sizes.split(",")]
    sim = simulation_rows(args.repeats)
    rows = (
        sim
        if args.only_simulation
        else lq_rows(sizes, args.repeats)
        + h2_rows(sizes, args.repeats)
        + fe_rows(args.repeats)
        + sim
    )
    print(
        "| gradient | size | parameters | objective (ms) | objective + gradient (ms) "
        "| ratio | central FD ratio |"
    )
    print("|---|---|---:|---:|---:|---:|---:|")
    for kind, size, P, t_obj, t_grad in rows:
        print(
            f"| {kind} | {size} | {P} | {1e3 * t_obj:.2f} | {1e3 * t_grad:.2f} "
            f"| {t_grad / t_obj:.2f} | {2 * P + 1} |"
        )


if __name__ == "__main__":
    main()
