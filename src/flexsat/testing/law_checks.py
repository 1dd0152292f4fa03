r"""The conformance checks of a control law (:class:`~flexsat.control.base.Controller`) on the
plant it is written for.

* ``channels_declared`` -- ``reads`` and ``writes`` are declared (no default), unique, name the
  plant's output and input channels (:func:`~flexsat.sim.engine.check_law`), and any
  ``read_sizes``/``write_sizes`` are the plant's channel sizes.
* ``shapes`` -- called on measurements of 1 and 3 cases (or its own count of per-case
  parameters) it returns one finite command per written channel of shape (n_cases,) or
  (n_cases, size).
* ``batch_equals_singles`` -- a law with shared parameters gives each case of a batch of 3 the
  commands of that case alone over a few samples, to the round-off bound
  4 n_t (p + n_ξ) ε max|terms| (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd
  ed., SIAM 2002, §3.1, carried over n_t samples).
* ``linear_form`` -- the law's :meth:`~flexsat.control.base.Controller.linear_form`, run by the
  reference loop :func:`~flexsat.control.linear_form.run_linear_law`, reproduces the law called
  sample by sample (:func:`~flexsat.control.linear_form.run_controller`) on random measurements,
  to 4 n_t ε (max|u| + max|u_ff| + max|D||e|) ρ^n_t, ρ >= 1 the spectral radius of its state
  matrix (the round-off of the two recursions, amplified at most by the law's own dynamics).
  Skipped for a law that declares no linear form.
* ``determinism`` -- the law called twice from its initial state gives the same bits, and two
  closed-loop runs on the plant with the same seeds (a random disturbance) are equal bit for bit.
* ``bad_input`` -- a plant lacking a channel the law reads, or writes, is refused by
  :func:`~flexsat.sim.engine.check_law` with a ValueError naming the channel.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from flexsat.control.base import Controller
from flexsat.control.linear_form import run_controller, run_linear_law
from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim.channels import ChannelDisturbance
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import check_law, simulate
from flexsat.testing.checks import (
    CHECK_RATE,
    CHECK_SAMPLES,
    EPS,
    Check,
    assert_close,
    magnitude,
    sample_states,
)

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

#: samples of the law-against-itself comparisons
LAW_SAMPLES = 12


class LawSubject:
    """A law, its plant and the sample sizes its checks use (as
    :class:`~flexsat.testing.plant_checks.PlantSubject`)."""

    def __init__(
        self,
        law: Controller,
        plant: Plant,
        state_scale: float,
        seed: int,
        rest_state: npt.ArrayLike | None = None,
    ) -> None:
        self.law, self.plant, self.name = law, plant, type(law).__name__
        self.state_scale, self.seed, self.rest_state = state_scale, seed, rest_state

    def call(self, times: FloatArray, Y: FloatArray) -> FloatArray:
        """The law's commands called sample by sample on Y, with the plant's channel widths."""
        return run_controller(self.law, times, Y, *self.sizes)

    def states(self, nc: int, offset: int = 0) -> FloatArray:
        return sample_states(self.plant, nc, self.seed + offset, self.state_scale, self.rest_state)

    @property
    def sizes(self) -> tuple[tuple[int, ...], tuple[int, ...]]:
        outs = {c.name: c.size for c in self.plant.outputs}
        ins = {c.name: c.size for c in self.plant.inputs}
        return tuple(outs[k] for k in self.law.reads), tuple(ins[k] for k in self.law.writes)

    def law_cases(self) -> tuple[int, ...]:
        n = self.law.n_cases
        pc = self.plant.n_cases
        if pc != 1:
            return (pc,)
        return (1, 3) if n == 1 else (n,)

    def measurements(self, nc: int, offset: int = 0) -> dict[str, FloatArray]:
        """The plant's outputs the law reads at sample states, zero input."""
        p = self.plant
        x = self.states(nc, offset)
        u = np.zeros((nc, p.n_inputs))
        return {k: np.asarray(p.output(k, x, u)) for k in self.law.reads}

    def sequence(self, nc: int) -> FloatArray:
        """Measurements (n_t, n_cases, p) over LAW_SAMPLES samples, channels in reads order."""
        rows = []
        for k in range(LAW_SAMPLES):
            y = self.measurements(nc, offset=k)
            # a law reading nothing (an open-loop table) is fed an empty (nc, 0) measurement
            columns = [y[n].reshape(nc, -1) for n in self.law.reads] or [np.zeros((nc, 0))]
            rows.append(np.concatenate(columns, axis=1))
        return np.stack(rows)

    def times(self) -> FloatArray:
        return np.arange(LAW_SAMPLES) / CHECK_RATE


def _commands(law: Controller, u: FloatArray | Mapping[str, FloatArray]) -> dict[str, FloatArray]:
    return dict(u) if isinstance(u, Mapping) else {law.writes[0]: u}


def channels_declared(s: LawSubject) -> None:
    law = s.law
    for field in ("reads", "writes"):
        names = getattr(law, field, None)
        assert isinstance(names, tuple), f"{field}: must be a tuple of names, got {names!r}"
        dup = sorted({n for n in names if names.count(n) > 1})
        assert not dup, f"{field}: {dup} appear twice"
    assert law.writes, "writes: the law writes no channel"
    try:
        check_law(s.plant, law)
    except ValueError as exc:
        raise AssertionError(str(exc)) from None
    rs, ws = s.sizes
    for field, want in (("read_sizes", rs), ("write_sizes", ws)):
        given = getattr(law, field, None)
        if given is not None:
            assert tuple(given) == want, f"{field}: {tuple(given)}, the plant's sizes are {want}"


def shapes(s: LawSubject) -> None:
    law = s.law
    _, ws = s.sizes
    for nc in s.law_cases():
        if getattr(law, "reference", None) is not None:  # as the engine does
            # duck-typed as the engine and run_controller: a law with a reference (a SlewLaw's)
            # tabulates it
            law.tabulate_reference(s.times())  # type: ignore[attr-defined]
        u, state = law(0.0, s.measurements(nc), law.initial_state(nc))
        cmd = _commands(law, u)
        assert set(cmd) == set(law.writes), f"commands: {sorted(cmd)} for writes {law.writes}"
        for name, size in zip(law.writes, ws):
            want = (nc,) if size == 1 else (nc, size)
            got = np.shape(cmd[name])
            assert got == want, f"command {name}: shape {got} for {nc} cases, expected {want}"
            assert np.isfinite(cmd[name]).all(), f"command {name}: non-finite"
        assert isinstance(state, dict), f"state: the next state must be a dict, got {type(state)}"


def batch_equals_singles(s: LawSubject) -> None:
    Y = s.sequence(3)
    times = s.times()
    batch = s.call(times, Y)
    # relative to the largest command: the law's terms are not known here, and a batch of a
    # law's own arithmetic rounds as its single case to within this
    tol = 4 * LAW_SAMPLES * (Y.shape[-1] + 1) * EPS * magnitude(batch)
    for i in range(3):
        alone = s.call(times, Y[:, i : i + 1])
        assert_close("commands", batch[:, i : i + 1], alone, tol, f"case {i} of 3 vs alone")


def linear_form(s: LawSubject) -> None:
    law = s.law
    nc = s.law_cases()[-1]
    times = s.times()
    form = law.linear_form(1.0 / CHECK_RATE, times, nc)
    # the check is skipped for a law whose linear_form() is None (_skip)
    assert form is not None, "linear_form: None (the check applies only to a linear law)"
    assert form.reads == tuple(law.reads) and form.writes == tuple(law.writes), (
        f"linear_form: channels {form.reads} -> {form.writes}, the law's {law.reads} -> "
        f"{law.writes}"
    )
    Y = s.sequence(nc)
    fast, slow = run_linear_law(form, Y), s.call(times, Y)
    e = np.abs(Y - form.y_ref)
    terms = np.einsum(
        "tcij,tcj->tci", np.abs(form.Dk), np.broadcast_to(e, Y.shape[:2] + e.shape[2:])
    )
    rho = 1.0
    if form.n_states:
        rho = max(
            1.0,
            max(
                float(np.abs(np.linalg.eigvals(a)).max())
                for a in form.Ak.reshape((-1,) + form.Ak.shape[-2:])
            ),
        )
    tol = 4 * LAW_SAMPLES * EPS * (magnitude(slow) + magnitude(form.u_ff) + magnitude(terms))
    assert_close("commands", fast, slow, tol * rho**LAW_SAMPLES, "linear form vs the law's calls")


def determinism(s: LawSubject) -> None:
    law = s.law
    Y = s.sequence(s.law_cases()[-1])
    a, b = s.call(s.times(), Y), s.call(s.times(), Y)
    assert np.array_equal(a, b), "commands: two runs from the initial state differ"
    p = s.plant
    names = [c.name for c in p.inputs]
    noisy = next((k for k in p.noise_channels if k in names), None)
    disturbances = {} if noisy is None else {noisy: ChannelDisturbance(random=1e-3)}
    config = SimConfig(
        duration=CHECK_SAMPLES / CHECK_RATE,
        control_rate=CHECK_RATE,
        seed=3,
        channel_disturbances=disturbances,
    )
    nc = s.law_cases()[-1]
    x0 = s.states(nc)
    runs = [simulate(p, law, config, n_cases=nc, initial_state=x0) for _ in range(2)]
    for name in runs[0].dataset.data_vars:
        va, vb = runs[0].dataset[name].values, runs[1].dataset[name].values
        assert np.array_equal(va, vb, equal_nan=True), f"{name}: two closed-loop runs differ"


class _Without(Plant):
    """The plant's channels less one (a plant a law must be refused on): only its channel
    declarations are read (:func:`~flexsat.sim.engine.check_law`)."""

    def __init__(self, plant: Plant, missing: str) -> None:
        self.inputs = tuple(c for c in plant.inputs if c.name != missing) or (
            Channel("other_input", ""),
        )
        self.outputs = tuple(c for c in plant.outputs if c.name != missing)
        self._nx = plant.nx

    @property
    def nx(self) -> int:
        return self._nx

    def linear_part(self) -> tuple[FloatArray, FloatArray]:
        raise AssertionError("only the channel declarations of this plant are read")


def bad_input(s: LawSubject) -> None:
    law = s.law
    for role, names in (("reads", law.reads), ("writes", law.writes)):
        if not names:
            continue
        name = names[0]
        try:
            check_law(_Without(s.plant, name), law)
        except ValueError as exc:
            assert str(exc).startswith(f"{name}:"), (
                f"{role}: the refusal does not start with the channel {name!r}: {exc}"
            )
            continue
        raise AssertionError(f"{role}: a plant without {name!r} was accepted")


LAW_CHECKS = (channels_declared, shapes, batch_equals_singles, linear_form, determinism, bad_input)


def _skip(s: LawSubject, name: str) -> str | None:
    """Why check ``name`` does not apply, from the law's declarations (None: it applies)."""
    law = s.law
    if (
        name == "linear_form"
        and law.linear_form(1.0 / CHECK_RATE, s.times(), s.law_cases()[-1]) is None
    ):
        return "the law declares no linear form (linear_form() is None)"
    if name == "batch_equals_singles" and (law.n_cases != 1 or s.plant.n_cases != 1):
        return "the law carries per-case parameters: its cases are not one law"
    return None


def controller_checks(
    law: Controller,
    plant: Plant,
    *,
    state_scale: float = 1e-2,
    seed: int = 0,
    rest_state: npt.ArrayLike | None = None,
) -> list[Check]:
    """The conformance checks of ``law`` on ``plant`` (module docstring).

    Parameters
    ----------
    law : Controller
    plant : Plant
        The plant the law is written for (its channels, and the measurements it is fed).
    state_scale : float
        1σ of the sample state perturbation about rest, SI.
    seed : int
        Seed of the samples.
    rest_state : array (n_x,), optional
        The state the samples perturb (default the plant's ``initial_state``): a working point
        of the law (a tether's length), SI.

    Returns
    -------
    list of :class:`~flexsat.testing.checks.Check`
    """
    s = LawSubject(law, plant, state_scale, seed, rest_state)
    out = [Check(s.name, "channels_declared", lambda: channels_declared(s))]
    reads, writes = getattr(law, "reads", None), getattr(law, "writes", None)
    declared = (
        isinstance(reads, tuple)
        and isinstance(writes, tuple)
        and set(reads) <= {c.name for c in plant.outputs}
        and set(writes) <= {c.name for c in plant.inputs}
    )
    for fn in LAW_CHECKS[1:]:
        skip = (
            _skip(s, fn.__name__)
            if declared
            else "the law's reads/writes are not channels of the plant (channels_declared)"
        )
        out.append(Check(s.name, fn.__name__, functools.partial(fn, s), skip))
    return out


__all__ = ["LAW_CHECKS", "LawSubject", "controller_checks"]
