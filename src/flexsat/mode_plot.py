"""Mode-shape and frequency plots for ``flexsat modes --plot``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

#: largest deflection drawn, as a fraction of the structure's size
DEFLECTION_FRACTION = 0.12


def _edges(structure) -> list[tuple[int, int]]:
    return [structure.element(e)["nodes"] for e in range(structure.n_elements)]


def plot_case_modes(case, n_modes: int, path, title: str) -> Path:
    """Write a PNG of the case's first ``n_modes`` modes (at most 6 panels).

    A case with a finite-element ``structure()`` gets its mode shapes drawn on the undeformed
    wireframe; any other case gets its frequencies (with descriptions, where it has them).
    """
    path = Path(path)
    structure = case.structure() if hasattr(case, "structure") else None
    fig = (
        _mode_shapes(structure, n_modes, title)
        if structure is not None
        else _frequency_chart(case, n_modes, title)
    )
    fig.savefig(path, dpi=110)
    return path


def _mode_shapes(structure, n_modes: int, title: str) -> Figure:
    assembly = structure.assemble()
    n_rigid_max = 6 if assembly.n_clamped == 0 else 0
    modes = assembly.modes(min(assembly.n_dofs, n_modes + n_rigid_max))
    omegas = modes.omegas
    # near-zero (rigid-body) modes sit many decades below the elastic ones computed with them
    elastic = np.flatnonzero(omegas > 1e-3 * max(omegas.max(), 1e-300))[: min(n_modes, 6)]
    xyz, ids = assembly.coordinates, list(assembly.node_ids)
    row = {nid: i for i, nid in enumerate(ids)}
    edges = [(row[a], row[b]) for a, b in _edges(structure)]
    size = np.ptp(xyz, axis=0).max() or 1.0
    shapes = modes.at_nodes()[:, :, :3]
    cols = min(3, len(elastic))
    rows = int(np.ceil(len(elastic) / cols))
    fig = Figure(figsize=(4.2 * cols, 3.8 * rows))
    fig.suptitle(title)
    for k, mode in enumerate(elastic):
        ax = fig.add_subplot(rows, cols, k + 1, projection="3d")
        u = shapes[mode]
        scale = DEFLECTION_FRACTION * size / max(np.abs(u).max(), 1e-300)
        for a, b in edges:
            ax.plot(*xyz[[a, b]].T, color="0.8", lw=0.6)
            ax.plot(*(xyz[[a, b]] + scale * u[[a, b]]).T, color="C0", lw=1.0)
        ax.set_title(f"mode {mode + 1}: {omegas[mode] / (2 * np.pi):.4g} Hz", fontsize=9)
        ax.set_axis_off()
        ax.set_box_aspect(np.maximum(np.ptp(xyz, axis=0), 0.05 * size))
    fig.tight_layout()
    return fig


def _frequency_chart(case, n_modes: int, title: str) -> Figure:
    f = np.asarray(case.frequencies_hz(n_modes))
    labels = case.mode_descriptions(n_modes) if hasattr(case, "mode_descriptions") else None
    fig = Figure(figsize=(8, 0.45 * len(f) + 1.5))
    ax = fig.add_subplot()
    y = np.arange(len(f))[::-1]
    ax.barh(y, f, color="C0")
    ax.set_yticks(
        y,
        [f"mode {i + 1}" + (f": {labels[i]}" if labels else "") for i in range(len(f))],
        fontsize=8,
    )
    ax.set_xlabel("frequency (Hz)")
    ax.set_title(title)
    fig.tight_layout()
    return fig
