"""Frequency-domain benchmark (issue 24): Bode and margins of the 45-mode EPS loop <= 0.5 s.

Times (wall and process CPU, best and median of N, one BLAS thread) of the analysis the example
``examples/frequency_domain.py`` prints, for two sampled-data loops broken at the plant input:

* EPS AttitudeLQG, 45 modes, 10 Hz (the example's design);
* TAMU Law I (g1 = 600 oz-in/rad, g2 = 800 oz-in-s/rad), 75 Hz, one sample of delay.

Stages: (a) ``build``: the law's discrete form and the loop (``discrete_law`` + ``build_loop``);
(b) ``bode``: the loop's response on 1,000 log-spaced frequencies up to the Nyquist frequency,
every channel (``frequency_response``); (c) ``margins``: gain, phase and delay margins of every
channel broken with the others closed (``build_loop(..., "torque[i]")`` + ``loop_margins``);
(d) ``disk``: the loop-at-a-time and multiloop disk margins (``disk_margins``); ``total`` is
(a)–(d) in one go. Design of the laws is not timed.

    PYTHONPATH=src OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/bench_frequency.py
    ... bench_frequency.py --baseline /tmp/fb-base/src   # side by side with another tree

With ``--baseline SRC`` every repeat runs the current tree and the baseline's ``src`` in their
own interpreters, alternating, and prints both with their ratio. Never collected by pytest.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

STAGES = ("build", "bode", "margins", "disk", "total")


def _eps_case():  # noqa: ANN202 - benchmark helper
    import numpy as np

    from flexsat.cases.eps import eps
    from flexsat.control import AttitudeLQG
    from flexsat.dynamics import linearize_attitude

    lin = linearize_attitude(eps().plant(n_modes=45))
    n = lin.A.shape[0]
    Q = np.diag([100 / 0.25**2] * 3 + [10.0] * 3 + [1.0] * (n - 6))
    law = AttitudeLQG.design(
        lin, Q, 1e-3 * np.eye(3), np.eye(3), np.diag([1e-6] * 3 + [1e-4] * 3), 0.1
    )
    return lin.to_statespace("eps"), law, 0.1, 0, ["torque[0]", "torque[1]", "torque[2]"]


def _tamu_case():  # noqa: ANN202 - benchmark helper
    from flexsat.cases.tamu import tamu
    from flexsat.dynamics.linear_model import plant_state_space

    case = tamu()
    law = case.law_i("600 ozf*in/rad", "800 ozf*in*s/rad", 0.0)
    return plant_state_space(case.model()), law, 1 / 75, 1, ["torque"]


def _stages(plant, law, dt, delay, channels):  # noqa: ANN001, ANN202
    import math

    import numpy as np

    from flexsat.analysis.frequency_domain import build_loop, frequency_response
    from flexsat.analysis.margins import disk_margins, loop_margins
    from flexsat.control.state_space_export import discrete_law

    state: dict = {}

    def build():  # noqa: ANN202
        state["K"] = discrete_law(law, dt, delay=delay)
        state["loop"] = build_loop(plant, state["K"], "input")
        return state["loop"]

    def bode():  # noqa: ANN202
        w = np.geomspace(1e-3, math.pi / dt, 1000)
        return frequency_response(state["loop"].transfer, omega_rad_s=w)

    def margins():  # noqa: ANN202
        return [loop_margins(build_loop(plant, state["K"], c)) for c in channels]

    def disk():  # noqa: ANN202
        return disk_margins(state["loop"])

    def total():  # noqa: ANN202
        build(), bode(), margins()
        return disk()

    return {"build": build, "bode": bode, "margins": margins, "disk": disk, "total": total}


def measure(repeats: int) -> dict:
    """{case: {stage: [(wall, cpu), ...]}} and a fingerprint of the results."""
    out: dict = {}
    for name, make in (("EPS LQG 45 modes", _eps_case), ("TAMU Law I", _tamu_case)):
        fns = _stages(*make())
        fns["total"]()  # warm: imports, first calls
        times: dict = {s: [] for s in STAGES}
        for _ in range(repeats):
            for s in STAGES:
                w, c = time.perf_counter(), time.process_time()
                res = fns[s]()
                times[s].append((time.perf_counter() - w, time.process_time() - c))
                if s == "margins":
                    pm = [round(m.phase_margin_deg, 3) for m in res]
                if s == "disk":
                    alphas = [round(d.alpha, 4) for d in res[0]] + [round(res[1].alpha, 4)]
        out[name] = {"times": times, "phase_margins_deg": pm, "disk_alphas": alphas}
    return out


def _child(src: str, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=src)
    proc = subprocess.run(
        [sys.executable, __file__, "--json", "--repeats", str(repeats)],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(proc.stdout)


def _summary(samples: list) -> tuple[float, float, float, float]:
    walls, cpus = [s[0] for s in samples], [s[1] for s in samples]
    return min(walls), statistics.median(walls), min(cpus), statistics.median(cpus)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--rounds", type=int, default=3, help="alternations with --baseline")
    ap.add_argument("--baseline", help="the src directory of a baseline tree")
    ap.add_argument("--json", action="store_true", help="print raw samples as JSON")
    args = ap.parse_args()
    if args.json:
        print(json.dumps(measure(args.repeats)))
        return
    here = str(Path(__file__).resolve().parents[1] / "src")
    trees = {"this tree": here} | ({"baseline": args.baseline} if args.baseline else {})
    runs: dict = {t: {} for t in trees}
    for _ in range(args.rounds if args.baseline else 1):
        for tree, src in trees.items():  # alternating, each in its own interpreter
            for case, res in _child(src, args.repeats).items():
                slot = runs[tree].setdefault(case, {"times": {s: [] for s in STAGES}})
                for s in STAGES:
                    slot["times"][s] += res["times"][s]
                slot["check"] = (res["phase_margins_deg"], res["disk_alphas"])
    print(f"load average at the end: {os.getloadavg()[0]:.2f} (2 cores)")
    for case in runs["this tree"]:
        for tree in runs:
            pm, alphas = runs[tree][case]["check"]
            print(f"\n{case} ({tree}): PM {pm} deg, disk α {alphas}")
        print(
            "| stage | wall best / median (s) | CPU best / median (s) |"
            + (
                " baseline wall best / median | baseline CPU best / median | CPU ratio |"
                if args.baseline
                else ""
            )
        )
        for s in STAGES:
            wb, wm, cb, cm = _summary(runs["this tree"][case]["times"][s])
            row = f"| {s} | {wb:.3f} / {wm:.3f} | {cb:.3f} / {cm:.3f} |"
            if args.baseline:
                bwb, bwm, bcb, bcm = _summary(runs["baseline"][case]["times"][s])
                row += f" {bwb:.3f} / {bwm:.3f} | {bcb:.3f} / {bcm:.3f} | {bcm / cm:.1f}× |"
            print(row)


if __name__ == "__main__":
    main()
