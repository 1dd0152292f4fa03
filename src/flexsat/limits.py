"""Resource limits: what one run may ask of the machine, checked before anything runs.

A scenario or an API call that exceeds one of these is refused up front with a message naming
the field, the limit and why it exists, instead of hanging, running out of memory or
overflowing. The limits are sized for a workstation (a few GB of memory, one core): a run at
the limit finishes in minutes. They are module constants so that a user with a bigger machine
can raise them deliberately (``flexsat.limits.MAX_SAMPLES = ...``): the checks of a run read
them at call time (the scenario schema's bounds on counts when flexsat.scenarios is imported).
"""

from __future__ import annotations

import numpy as np

from flexsat.input_checks import FieldError

#: control samples of one run (duration × control rate): at ~50-100 µs per control step
#: (docs/performance.md) the limit is a few minutes of simulation
MAX_SAMPLES = 2_000_000

#: integrator substeps per control period (a stiff friction law asks for more, see
#: :func:`flexsat.sim.config.stable_substeps`)
MAX_SUBSTEPS = 1_000

#: integrator steps of one run (control samples × substeps): minutes on one core
MAX_INTEGRATOR_STEPS = 20_000_000

#: right-hand-side evaluations of one continuous-law run (the adaptive DOP853 of
#: :mod:`flexsat.sim.continuous`, a Python law and plant: ~0.3 ms each for the tether, so the
#: limit is ~5 minutes). Estimated from the closed loop's fastest rate before a tether run
#: (:func:`flexsat.cases.tether.check_continuous_cost`), and counted during every run, which
#: ends with an error at the limit: an explicit integrator on a stiff loop (a gain of 1e12)
#: takes steps ~1/|fastest rate| and would otherwise crawl for hours
MAX_ADAPTIVE_EVALUATIONS = 1_000_000

#: passes of one iterated fit (the Gauss-Newton identifications of :mod:`flexsat.identify`, each
#: pass a dense eigen-solve of the model): they converge in 5-30 passes when the data determine
#: the parameters (quadratically near the solution), so a fit still moving after 1,000 is not
#: converging, and more passes only spend time (seconds per pass on a few thousand dofs)
MAX_FIT_ITERATIONS = 1_000

#: noisy copies of one parametric bootstrap (:func:`flexsat.identify.era.bootstrap_uncertainty`),
#: each an ERA of the copy (~0.05 s for a 200 x 200 Hankel matrix, so ~10 minutes at the limit);
#: the standard deviations it estimates carry a relative error 1/sqrt(2 n), 0.7 % at the limit
MAX_BOOTSTRAP_SAMPLES = 10_000

#: estimated memory of one run's histories, bytes (samples × cases × recorded values × 8)
MAX_MEMORY = 2 * 1024**3

#: cases of one batch (an array of gains or a Monte Carlo set)
MAX_CASES = 100_000

#: runs of one scenario file
MAX_RUNS = 100

#: elastic modes of a simulated plant: building the assumed-modes model of the TAMU case takes
#: ~2 s with 100 modes and grows with the cube (30 s with 200)
MAX_MODES = 100

#: finite elements of a case's structural mesh (dense eigen-solves of 3-6 dofs per node)
MAX_ELEMENTS = 1_000

#: stars of one catalogue (Tycho-2 holds 2.5 million; Hipparcos 118,218): ~40 bytes each, plus
#: the pair index below
MAX_CATALOG_STARS = 3_000_000

#: catalogue pairs of a star-pattern pair index (pairs closer than a camera's field): ~24 bytes
#: each, plus the sort (Hipparcos with a 20° field would need ~10⁸ pairs, ~3 GB)
MAX_CATALOG_PAIRS = 20_000_000

#: candidate matches of one field of view's measured pairs against the pair index (measured
#: pairs × catalogue pairs within the tolerance), ~100 bytes each in the voting
MAX_PAIR_CANDIDATES = 4_000_000

#: largest ratio of two nonzero weights of one LQR-type design (a slew's Q and D, a simulation
#: run's state and input weights): beyond ~1/ε (ε = 2.2e-16) the smaller weight is below the
#: rounding of the larger in the Riccati equation, so it weighs nothing and the solver fails
#: without saying which weight (the examples span at most 1e10)
MAX_WEIGHT_RANGE = 1e15

#: largest noise seed (numpy's seeds are unbounded, but seed + case index must stay an int64)
MAX_SEED = 2**32 - 1

#: scenario documents (a few kB each): size of the text; nesting depth of its mappings and
#: lists, checked before the YAML parser recurses into them; the number of values, as parsed
#: and once aliases (``*anchor``) are expanded, which bounds the work of parsing (pure-Python
#: YAML: ~10 µs per value) and validating them
MAX_DOCUMENT_BYTES = 256_000
MAX_NESTING = 32
MAX_DOCUMENT_NODES = 10_000


def is_integral(value: object) -> bool:
    """True for an int or a float with an integral value (``1e3``); False for bools, NaN,
    infinities, fractions and non-numbers (compared without a float conversion, so that an
    int of any size is safe)."""
    if isinstance(value, (bool, np.bool_)):
        return False
    if isinstance(value, (int, np.integer)):
        return True
    return isinstance(value, (float, np.floating)) and float(value).is_integer()


def _bytes(n: float) -> str:
    for unit, size in (("GB", 1024**3), ("MB", 1024**2), ("kB", 1024)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def check_count(value: float, limit: int, field: str, what: str, hint: str = "") -> None:
    """Refuse ``value`` above ``limit`` with ``"field: <what> = value exceeds the limit ..."``.

    Parameters
    ----------
    value : float
        The count (a product such as duration × control_rate need not be an integer).
    limit : int
    field : str
        The input to blame (message head).
    what : str
        What is counted, e.g. ``"the run needs 3e9 control samples (duration × control_rate)"``.
    hint : str
        How to stay within the limit.

    Raises
    ------
    flexsat.input_checks.FieldError
        With ``field`` as its :attr:`~flexsat.input_checks.FieldError.field`.
    """
    if value > limit:
        raise FieldError(
            field,
            f"{what} = {value:.4g}, above the limit {limit:,} "
            f"(flexsat.limits){'; ' + hint if hint else ''}",
        )


def memory_estimate(n_samples: int, n_cases: int, n_values: int) -> int:
    """Bytes of ``n_values`` float64 histories of ``n_samples`` × ``n_cases``."""
    return 8 * int(n_samples) * int(n_cases) * int(n_values)


def check_memory(n_bytes: int, field: str, what: str) -> None:
    """Refuse an estimated memory above :data:`MAX_MEMORY`.

    Raises
    ------
    flexsat.input_checks.FieldError
        ``"field: <what> needs about 12 GB of memory, above the limit 2 GB ..."``.
    """
    if n_bytes > MAX_MEMORY:
        raise FieldError(
            field,
            f"{what} needs about {_bytes(n_bytes)} of memory, above the "
            f"limit {_bytes(MAX_MEMORY)} (flexsat.limits.MAX_MEMORY)",
        )


__all__ = [
    "MAX_ADAPTIVE_EVALUATIONS",
    "MAX_BOOTSTRAP_SAMPLES",
    "MAX_CASES",
    "MAX_CATALOG_PAIRS",
    "MAX_CATALOG_STARS",
    "MAX_DOCUMENT_BYTES",
    "MAX_DOCUMENT_NODES",
    "MAX_FIT_ITERATIONS",
    "MAX_MODES",
    "MAX_ELEMENTS",
    "MAX_INTEGRATOR_STEPS",
    "MAX_MEMORY",
    "MAX_NESTING",
    "MAX_PAIR_CANDIDATES",
    "MAX_RUNS",
    "MAX_SAMPLES",
    "MAX_SEED",
    "MAX_SUBSTEPS",
    "MAX_WEIGHT_RANGE",
    "check_count",
    "check_memory",
    "is_integral",
    "memory_estimate",
]
