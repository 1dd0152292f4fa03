"""The compiled closed loop's parameter and output records, their allocation, and the cached
numba decorator of its kernels (:mod:`flexsat.sim.kernels`, :mod:`flexsat.sim.kernel_phases`).

The kernels take their parameters as one record, :class:`Loop` (a named tuple of arrays and
scalars, numba-typed field by field: the attribute reads compile to the same loads as
positional arguments), and write either the histories of :class:`Records` or the running
reductions of :class:`Reductions`. Shapes and meanings: :func:`flexsat.sim.kernels.closed_loop`
and :func:`flexsat.sim.kernels.closed_loop_reduced`.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np
from numba import njit

__all__ = [
    "ARGUMENTS",
    "Loop",
    "Records",
    "Reductions",
    "RECORDS",
    "REDUCTIONS",
    "allocate_records",
    "cached_jit",
    "case_index",
]

#: the functions compiled without the on-disk cache (one warning for the kernels)
_UNCACHED: list[str] = []


def cached_jit(**options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``njit(cache=True, **options)``; where numba finds no writable cache directory (a
    read-only install without a writable home) it refuses to cache at decoration time, and
    the kernels are compiled in each process instead (a warning says so: a few seconds).

    Every kernel function is a module-level function: numba's cache is keyed by the qualified
    name, so functions made by a factory (closures of one name) would overwrite each other."""

    def wrap(function: Callable[..., Any]) -> Any:
        try:
            return njit(cache=True, **options)(function)
        except RuntimeError as exc:
            if _UNCACHED:  # one warning for the kernels
                return njit(**options)(function)
            _UNCACHED.append(function.__name__)
            warnings.warn(
                f"flexsat.sim.kernels: {exc}; compiling without the on-disk cache "
                "(set NUMBA_CACHE_DIR to a writable directory to keep it)",
                RuntimeWarning,
                stacklevel=2,
            )
            return njit(**options)(function)

    return wrap


class Loop(NamedTuple):
    """The parameters of a closed loop (shapes and meanings:
    :func:`flexsat.sim.kernels.closed_loop`)."""

    x0: np.ndarray
    E: np.ndarray
    block_diagonal: bool
    P1u: np.ndarray
    P1f: np.ndarray
    P2f: np.ndarray
    Cr: np.ndarray
    fric: np.ndarray
    substeps: int
    imp_k: np.ndarray
    imp_dx: np.ndarray
    Cm: np.ndarray
    Dm: np.ndarray
    Dmf: np.ndarray
    sensor: np.ndarray
    sensor_slot: np.ndarray
    fir_src: int
    fir_dst: int
    fir_w: np.ndarray
    Ak: np.ndarray
    Bk: np.ndarray
    Ck: np.ndarray
    Dk: np.ndarray
    y_ref: np.ndarray
    u_ff: np.ndarray
    K0: np.ndarray
    act: np.ndarray
    dist_std: np.ndarray
    dist_slot: np.ndarray
    noise: np.ndarray
    bound: float
    Co: np.ndarray
    Do: np.ndarray
    Dof: np.ndarray
    Q: np.ndarray


class Records(NamedTuple):
    """What :func:`flexsat.sim.kernels.closed_loop` records (:func:`allocate_records`)."""

    X: np.ndarray
    Y: np.ndarray
    Ucmd: np.ndarray
    U: np.ndarray
    D: np.ndarray
    F: np.ndarray
    O: np.ndarray
    En: np.ndarray
    stop: np.ndarray


class Reductions(NamedTuple):
    """The reductions of :func:`flexsat.sim.kernels.closed_loop_reduced`: their definitions
    (inputs), then the arrays it writes."""

    red_c: np.ndarray
    red_tab: np.ndarray
    red_t: np.ndarray
    red_dir: np.ndarray
    red_band: np.ndarray
    snap_k: np.ndarray
    red: np.ndarray
    upeak: np.ndarray
    snapO: np.ndarray
    snapE: np.ndarray
    stop: np.ndarray


#: the fields of :class:`Loop`, :class:`Records` and :class:`Reductions` in order
ARGUMENTS, RECORDS, REDUCTIONS = Loop._fields, Records._fields, Reductions._fields


@cached_jit(inline="always", error_model="numpy")
def case_index(length: int, c: int) -> int:
    """Index of case c into a leading case axis of ``length`` 1 (shared) or C (per case)."""
    return 0 if length == 1 else c


def allocate_records(
    n_t: int,
    n_cases: int,
    n: int,
    m: int,
    p: int,
    record_states: bool,
    r: int = 0,
    energy: bool = False,
) -> Records:
    """Output arrays (X, Y, Ucmd, U, D, F, O, En, stop) of the kernels, case-major; X has
    time length 0 when the states are not recorded, O when there are no output rows (r = 0),
    En without ``energy``."""
    X = np.empty((n_cases, n_t if record_states else 0, n))
    return Records(
        X,
        np.empty((n_cases, n_t, p)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t, m)),
        np.empty((n_cases, n_t)),
        np.empty((n_cases, n_t if r else 0, r)),
        np.empty((n_cases, n_t if energy else 0)),
        np.full(n_cases, -1, dtype=np.int64),
    )
