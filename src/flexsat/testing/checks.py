"""What every conformance check shares: the named check, the runner and the sample data.

A check is a :class:`Check`: a name, the subject it checks and a function that raises an
:class:`AssertionError` saying why the subject fails, or a ``skip`` reason when the check does
not apply by the subject's own declaration (a plant whose ``energy`` is None has no energy
check; a plant with its own integrator cannot be dispersed). :func:`run_checks` runs a list
and turns the first failure, or any exception a check meets, into an AssertionError naming the
subject and the check.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import Controller
from flexsat.dynamics.plant import Plant

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

#: unit round-off of float64
EPS = float(np.finfo(float).eps)
#: control rate and length of the short closed-loop runs of the checks (20 samples)
CHECK_RATE, CHECK_SAMPLES = 20.0, 20


@dataclass(frozen=True)
class Check:
    """One named conformance check of one subject.

    Parameters
    ----------
    subject : str
        What is checked (the plant's or law's class name).
    name : str
        The check (``channels_declared``, ``shapes`` ...).
    run : callable
        Raises an AssertionError saying why the subject fails; returns None when it passes.
    skip : str or None
        Why the check does not apply to this subject (its declaration), or None.
    """

    subject: str
    name: str
    run: Callable[[], None]
    skip: str | None = None

    def __call__(self) -> None:
        """Run the check (nothing when it is skipped), failures as :func:`run_checks` says."""
        if self.skip is None:
            _run_one(self)

    def __str__(self) -> str:
        return f"{self.subject}-{self.name}"


def _run_one(check: Check) -> None:
    try:
        check.run()
    except AssertionError as exc:
        raise AssertionError(f"{check.subject} fails {check.name}: {exc}") from None
    except Exception as exc:  # a crash inside the subject is a failure of this check
        raise AssertionError(
            f"{check.subject} fails {check.name}: it raised {type(exc).__name__}: {exc}"
        ) from exc


def run_checks(checks: Iterable[Check]) -> list[Check]:
    """Run every check that applies; return the skipped ones.

    Raises
    ------
    AssertionError
        ``"<subject> fails <check>: <why>"`` for the first failing check.
    """
    skipped: list[Check] = []
    for check in checks:
        if check.skip is not None:
            skipped.append(check)
        else:
            _run_one(check)
    return skipped


def matvec(M: FloatArray, v: FloatArray) -> FloatArray:
    """M v over the case axis: M (r, c) or (n_cases, r, c), v (n_cases, c) -> (n_cases, r)."""
    return np.einsum("...ij,...j->...i", M, v)


def state_derivative(plant: Plant, x: FloatArray, u: FloatArray) -> FloatArray:
    """x' = A x + B u + B_f f(x, u), the split form of the plant protocol, (n_cases, n_x)."""
    A, B = plant.linear_part()
    xd = matvec(A, x) + matvec(B, u)
    if plant.nonlinear:
        Bf = plant.force_matrix
        # a nonlinear plant gives B_f (Plant.force_matrix; the ``shapes`` check asserts it)
        assert Bf is not None, "nonlinear: the plant is nonlinear but gives no force_matrix"
        xd = xd + matvec(Bf, plant.nonlinear_force(x, u))
    return xd


def cases_of(plant: Plant) -> tuple[int, ...]:
    """Batch sizes a plant is checked at: 1 and 3, or its own count when it is dispersed."""
    return (1, 3) if plant.n_cases == 1 else (plant.n_cases,)


def sample_states(
    plant: Plant, n_cases: int, seed: int, scale: float, rest_state: npt.ArrayLike | None = None
) -> FloatArray:
    """States (n_cases, n_x) near ``rest_state`` (default the plant's ``initial_state``):
    rest + scale N(0, 1), projected back onto the plant's manifold
    (:meth:`~flexsat.dynamics.plant.Plant.normalize`)."""
    rng = np.random.default_rng(seed)
    rest = plant.initial_state(n_cases) if rest_state is None else rest_state
    x0 = np.broadcast_to(rest, (n_cases, plant.nx))
    return plant.normalize(x0 + scale * rng.standard_normal((n_cases, plant.nx)))


def sample_inputs(plant: Plant, n_cases: int, seed: int, scale: float) -> FloatArray:
    """Inputs (n_cases, m): scale N(0, 1) in each channel's SI unit."""
    return scale * np.random.default_rng(seed).standard_normal((n_cases, plant.n_inputs))


def split_inputs(plant: Plant, u: FloatArray) -> dict[str, FloatArray]:
    """The concatenated inputs u (n_cases, m) as commands by channel name."""
    return {
        name: u[:, sl.start] if sl.stop - sl.start == 1 else u[:, sl]
        for name, sl in plant.input_slices.items()
    }


class HoldLaw(Controller):
    """Holds fixed commands on every input channel and reads nothing: the open-loop drive of
    the plant checks' short runs.

    Parameters
    ----------
    commands : dict of str to array
        Command per written channel, (n_cases,) or (n_cases, size), SI.
    """

    reads: tuple[str, ...] = ()

    def __init__(self, commands: Mapping[str, npt.ArrayLike]) -> None:
        self.writes = tuple(commands)
        self.commands = {k: np.asarray(v, float) for k, v in commands.items()}

    def __call__(
        self, t: float, y: Mapping[str, FloatArray], state: dict[str, FloatArray]
    ) -> tuple[dict[str, FloatArray], dict[str, FloatArray]]:
        return dict(self.commands), state


def assert_close(
    name: str, got: npt.ArrayLike, want: npt.ArrayLike, tol: float | FloatArray, what: str
) -> None:
    """|got − want| <= tol everywhere (NaN fails), or an AssertionError naming ``name``."""
    g, w = np.asarray(got, float), np.asarray(want, float)
    assert g.shape == w.shape, f"{name}: shape {g.shape}, expected {w.shape} ({what})"
    same_nan = np.isnan(g) & np.isnan(w)  # an undefined metric (never settled) in both
    assert np.array_equal(np.isnan(g), np.isnan(w)), f"{name}: NaN in one only ({what})"
    err = np.where(same_nan, 0.0, np.abs(g - w))
    bound = np.broadcast_to(np.asarray(tol, float), err.shape)  # a bound per entry, or one
    if err.size and not (err <= bound).all():
        k = np.unravel_index(np.argmax(err - bound), err.shape)  # the entry furthest over
        raise AssertionError(f"{name}: differs by {err[k]:.3g} > {bound[k]:.3g} ({what})")


def magnitude(*arrays: npt.ArrayLike) -> float:
    """Largest |entry| of the arrays (1 when all are zero), the scale of a round-off bound."""
    m = max((float(np.abs(a).max()) for a in arrays if np.size(a)), default=0.0)
    return m if m > 0 else 1.0


__all__ = [
    "CHECK_RATE",
    "CHECK_SAMPLES",
    "EPS",
    "Check",
    "HoldLaw",
    "assert_close",
    "cases_of",
    "magnitude",
    "matvec",
    "run_checks",
    "sample_inputs",
    "sample_states",
    "split_inputs",
    "state_derivative",
]
