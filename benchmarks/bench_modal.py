"""FEM modal benchmark: assembly and shift-invert Lanczos solve of a ~10,000-dof 3-D frame.

Model: a free-free cubic lattice of n x n x n nodes (default 12: 1,728 nodes, 10,368 dofs,
4,752 frame members, aluminium tubes 50 x 2 mm at 1 m pitch).  Timed separately (best of N):

* build: the Python calls add_node / add_frame;
* assemble: Structure.assemble() (batched element matrices, COO -> CSR);
* solve: Assembly.modes(6 + 50, rigid_body_modes=6), i.e. the 6 rigid-body and the first 50
  elastic modes, including the mass-matrix checks.

Target (issue #3): assembly well under 1 s, solve <= 5 s on the 2-core reference machine.
Prints a markdown table row; a plain script, never collected by pytest.

    .venv/bin/python benchmarks/bench_modal.py [--size 12] [--elastic 50] [--repeats 3]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from flexsat.structures import Material, Section, Structure

TARGET_ASSEMBLE_S = 1.0
TARGET_SOLVE_S = 5.0


def lattice(n: int) -> Structure:
    """Free-free cubic lattice of frame members, n nodes per edge, 1 m pitch."""
    material, section = Material(E=70e9, rho=2700.0), Section.tube(0.05, 0.002)
    s = Structure(f"lattice {n}^3")
    ids = np.arange(n**3).reshape(n, n, n)
    for (i, j, k), node in np.ndenumerate(ids):
        s.add_node(int(node), (float(i), float(j), float(k)))
    for axis in range(3):
        lo = [slice(None)] * 3
        hi = [slice(None)] * 3
        lo[axis], hi[axis] = slice(0, n - 1), slice(1, n)
        for a, b in zip(ids[tuple(lo)].ravel(), ids[tuple(hi)].ravel()):
            s.add_frame(int(a), int(b), material, section)
    return s


def best_of(repeats: int, fn):
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return min(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--size", type=int, default=12, help="nodes per lattice edge")
    parser.add_argument("--elastic", type=int, default=50, help="elastic modes to compute")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()

    t_build, structure = best_of(args.repeats, lambda: lattice(args.size))
    t_asm, asm = best_of(args.repeats, structure.assemble)
    n_modes = 6 + args.elastic
    t_solve, modes = best_of(args.repeats, lambda: asm.modes(n_modes, rigid_body_modes=6))

    orth = np.abs(modes.shapes.T @ asm.M @ modes.shapes - np.eye(n_modes)).max()
    residual = np.abs(asm.K @ modes.shapes - asm.M @ modes.shapes * modes.omegas**2).max()
    ok = t_asm < TARGET_ASSEMBLE_S and t_solve <= TARGET_SOLVE_S
    print(f"first elastic frequencies (Hz): {np.round(modes.frequencies_hz[6:12], 4)}")
    print(
        f"checks: max |Φ^T M Φ - I| = {orth:.1e}, max |KΦ - MΦΩ²| / max|K| = "
        f"{residual / abs(asm.K).max():.1e}"
    )
    print()
    print("| model | dofs | members | build (s) | assemble (s) | modes | solve (s) | target |")
    print("|---|---|---|---|---|---|---|---|")
    print(
        f"| free-free frame lattice {args.size}³ | {asm.n_dofs:,} | {structure.n_elements:,} "
        f"| {t_build:.3f} | {t_asm:.3f} | 6 rigid + {args.elastic} elastic | {t_solve:.2f} "
        f"| assemble < {TARGET_ASSEMBLE_S:g} s, solve ≤ {TARGET_SOLVE_S:g} s: "
        f"{'met' if ok else 'MISSED'} |"
    )


if __name__ == "__main__":
    main()
