"""Command-line start-up benchmark: wall time of ``flexsat --help``, ``flexsat cases`` and
``flexsat validate``, for a baseline source tree and the current one, side by side.

Each command runs in a fresh interpreter (a subprocess, as a user's shell starts it), through
the same launcher for both trees, ``python -c "from flexsat.cli import app; app()" ARGS`` with
``PYTHONPATH=<tree>/src`` and the same Python, so that only the package differs. Output goes to
/dev/null. Reported: best and median wall time of N runs, the best CPU time (user + system of
the child: what the wall time would be on an idle machine, since start-up is single-threaded),
the exit code, and the ratio baseline / current of the best wall times. A bare
``python -c pass`` row gives the interpreter's own start-up, which no package change can
remove. Targets (issue #9): ≤ 0.5 s for ``--help`` and ``cases``.

The baseline is the commit before the issue-9 work, checked out next to the repository::

    git worktree add --detach /tmp/flexsat-baseline 6d22c90
    .venv/bin/python benchmarks/bench_cli.py [--baseline /tmp/flexsat-baseline] [--repeats 7]

Without a baseline tree only the current one is timed. Prints a markdown table; a plain script,
never collected by pytest.
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
LAUNCHER = "import sys; from flexsat.cli import app; app(sys.argv[1:], prog_name='flexsat')"
#: (label, arguments, target in s or None); validate is slow enough for fewer repeats
COMMANDS = (
    ("flexsat --help", ["--help"], 0.5),
    ("flexsat cases", ["cases"], 0.5),
    ("flexsat validate", ["validate"], None),
)


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def time_command(
    src: Path | None, args: list[str], repeats: int
) -> tuple[list[float], list[float], int]:
    """Wall and CPU times of ``repeats`` fresh runs and the last exit code (``src`` None: bare
    interpreter)."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "COLUMNS": "120"}
    if src is None:
        argv = [sys.executable, "-c", "pass"]
    else:
        env["PYTHONPATH"] = str(src)
        argv = [sys.executable, "-c", LAUNCHER, *args]
    times, cpu, code = [], [], 0
    for _ in range(repeats):
        start, cpu0 = time.perf_counter(), _children_cpu()
        code = subprocess.run(
            argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        ).returncode
        times.append(time.perf_counter() - start)
        cpu.append(_children_cpu() - cpu0)
    return times, cpu, code


def _fmt(times: list[float], cpu: list[float]) -> str:
    return f"{min(times):.3f} s ({statistics.median(times):.3f} s); CPU {min(cpu):.3f} s"


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument(
        "--baseline",
        type=Path,
        default=Path("/tmp/flexsat-baseline"),
        help="source tree of the baseline (its src/ goes on PYTHONPATH)",
    )
    p.add_argument("--repeats", type=int, default=7, help="runs per fast command")
    p.add_argument("--validate-repeats", type=int, default=3, help="runs of validate")
    args = p.parse_args()

    trees = {"current": ROOT / "src"}
    if (args.baseline / "src" / "flexsat" / "cli.py").is_file():
        trees = {"baseline": args.baseline / "src", **trees}
    else:
        print(f"no baseline tree at {args.baseline}: timing the current tree only", file=sys.stderr)
    print(f"- date: {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    print(f"- machine: {platform.machine()}, {os.cpu_count()} logical CPUs ({platform.platform()})")
    print(f"- load average at start: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    print(
        f"- Python {platform.python_version()}; trees: "
        + ", ".join(f"{k} = {v}" for k, v in trees.items())
    )
    print()
    bare, bare_cpu, _ = time_command(None, [], args.repeats)
    header = ["command"] + [f"{k}: wall best (median); CPU best, exit" for k in trees]
    if "baseline" in trees:
        header.append("baseline / current")
    header.append("target")
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    print(
        "| `python -c pass` (interpreter only) | "
        + " | ".join(_fmt(bare, bare_cpu) for _ in trees)
        + (" | – " if "baseline" in trees else " ")
        + "| – |"
    )
    for label, argv, target in COMMANDS:
        repeats = args.validate_repeats if label.endswith("validate") else args.repeats
        best, best_cpu, cells = {}, {}, []
        for name, src in trees.items():
            times, cpu, code = time_command(src, argv, repeats)
            best[name], best_cpu[name] = min(times), min(cpu)
            cells.append(f"{_fmt(times, cpu)}, {code}")
        row = [f"`{label}`", *cells]
        if "baseline" in trees:
            row.append(f"**{best['baseline'] / best['current']:.1f}×**")
        if target is None:
            row.append("–")
        else:
            verdict = {
                k: "met" if v <= target else "NOT met"
                for k, v in (("wall", best["current"]), ("CPU", best_cpu["current"]))
            }
            row.append(f"≤ {target} s: wall {verdict['wall']}, CPU {verdict['CPU']}")
        print("| " + " | ".join(row) + " |")


if __name__ == "__main__":
    main()
