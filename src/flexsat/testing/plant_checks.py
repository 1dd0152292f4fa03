r"""The conformance checks of a plant (:class:`~flexsat.dynamics.plant.Plant`).

Each check states the property of the plant protocol it tests and the bound it allows:

* ``channels_declared`` -- inputs and outputs are :class:`~flexsat.dynamics.plant.Channel` s
  with unique identifier names (no name both an input and an output: the recorded dataset keys
  them alike), units that pint parses as SI (a conversion factor of exactly 1 to the base
  units), positive sizes; ``recorded``, ``noise_channels`` and a declared
  :attr:`~flexsat.dynamics.plant.Plant.maneuver` name channels the plant has, the latter
  with units rad, rad/s, N m, m, size 1, its angle a state coordinate and a
  ``vibration_energy``.
* ``shapes`` -- for 1 and 3 cases: the rest state is (n_cases, n_x), (A, B) and B_f have the
  protocol's shapes, the nonlinear force is (n_cases, n_f), every output is (n_cases,) or
  (n_cases, size) and finite, energy (n_cases,), momentum (n_cases,) or (n_cases, 3), power
  (n_cases,); with an extra leading time axis every output is the stack of its time slices.
* ``batch_equals_singles`` -- outputs, force, energy and power of a batch are those of each
  case alone, and the histories of a short run of 3 cases with per-case seeds are those of
  each case run alone with its seed (the metrics are read from them), both to the round-off
  bound of the products involved:
  4 (n_x + m) ε max|terms| per evaluation, times the number of samples for a run (Higham,
  *Accuracy and Stability of Numerical Algorithms*, 2nd ed., SIAM 2002, §3.1: a length-n dot
  product in any order is within γ_n Σ|terms| of the exact one).
* ``dispersion`` -- three copies stacked by :func:`~flexsat.dynamics.dispersion.stack_plants`
  behave per case: the same linear part, outputs, energy and run (round-off bound as above).
  Skipped for a plant with its own integrator (``step``), which stacking refuses.
* ``linear_form`` -- the split form x' = A x + B u + B_f f(x, u) is the plant's: ``nonlinear``
  is true exactly when B_f is given; the analytic ``force_jacobian`` (if any) is the central
  difference of the force; a plant's own integrator ``step`` has the split form as its
  derivative (Richardson-extrapolated difference quotient, bound: the change between two
  step sizes, the estimate of the next error term); a plant's ``rhs`` or ``derivative`` (if
  any) equals the split form to round-off; outputs with matrices equal ``output()``.
* ``energy`` -- dE/dt (central difference of ``energy`` along x') equals the declared
  ``power(x, u)`` (the inputs' work less the dissipation) or, without it, is <= 0 in free
  motion (a passive plant); angular momentum is constant in free motion. The bound is the
  Richardson estimate of the difference's truncation error (zero for the quadratic energy of a
  linear plant) plus its round-off 16 n_x ε max|E| / h. Skipped for a plant whose ``energy``
  is None.
* ``determinism`` -- two runs with the same seeds (a random disturbance on an input) are equal
  bit for bit, and a different seed changes them.
* ``bad_input`` -- an unknown output name, an unknown or non-finite or misshapen initial value
  and a misshapen or non-finite ``initial_state`` for :func:`~flexsat.sim.engine.simulate`
  are each a ValueError naming the field.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.dynamics.dispersion import stack_plants
from flexsat.dynamics.plant import Channel, Plant
from flexsat.sim.channels import ChannelDisturbance
from flexsat.sim.config import SimConfig
from flexsat.sim.engine import check_law, simulate
from flexsat.sim.instruments import unit_row
from flexsat.testing.checks import (
    CHECK_RATE,
    CHECK_SAMPLES,
    EPS,
    Check,
    HoldLaw,
    assert_close,
    cases_of,
    magnitude,
    matvec,
    sample_inputs,
    sample_states,
    split_inputs,
    state_derivative,
)
from flexsat.units import Q_

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.sim.recording import SimResult
    from flexsat.units import FloatArray

#: what a declared maneuver channel must be measured in
MANEUVER_UNITS = {"angle": "rad", "rate": "rad/s", "torque": "N*m", "deflection": "m"}


class PlantSubject:
    """A plant and the sample sizes its checks use.

    Parameters
    ----------
    plant : Plant
    state_scale : float
        1σ of the state perturbation about rest, SI per coordinate.
    input_scale : float
        1σ of the sample inputs, SI per channel.
    seed : int
        Seed of the sample states and inputs.
    rest_state : array (n_x,), optional
        The state the samples perturb; default the plant's ``initial_state``.
    """

    def __init__(
        self,
        plant: Plant,
        state_scale: float,
        input_scale: float,
        seed: int,
        rest_state: npt.ArrayLike | None = None,
    ) -> None:
        self.plant, self.name = plant, type(plant).__name__
        self.state_scale, self.input_scale, self.seed = state_scale, input_scale, seed
        self.rest_state = rest_state

    def states(self, n: int, offset: int = 0) -> FloatArray:
        return sample_states(self.plant, n, self.seed + offset, self.state_scale, self.rest_state)

    def inputs(self, n: int, offset: int = 1) -> FloatArray:
        return sample_inputs(self.plant, n, self.seed + offset, self.input_scale)

    def config(self, **kw: Any) -> SimConfig:
        return SimConfig(duration=CHECK_SAMPLES / CHECK_RATE, control_rate=CHECK_RATE, **kw)

    def noisy_input(self) -> str | None:
        """An input channel with a noise stream (a random disturbance can be put on it)."""
        names = [c.name for c in self.plant.inputs]
        return next((k for k in self.plant.noise_channels if k in names), None)

    def run(self, plant: Plant, n: int, seed: int = 0, noise: bool = True) -> SimResult:
        """The short open-loop run of ``plant`` (n cases) from the sample states, held sample
        inputs, a random disturbance on the first noisy input (``noise``)."""
        name = self.noisy_input() if noise else None
        disturbances = {} if name is None else {name: ChannelDisturbance(random=self.input_scale)}
        config = self.config(seed=seed, channel_disturbances=disturbances)
        law = HoldLaw(split_inputs(self.plant, self.inputs(n)))
        return simulate(plant, law, config, n_cases=n, initial_state=self.states(n))


# -- channels_declared ----------------------------------------------------------------------------
def _check_unit(ch: Channel, role: str) -> None:
    assert isinstance(ch.unit, str), f"{role} {ch.name}: unit must be a string, got {ch.unit!r}"
    try:
        q = Q_(1.0, ch.unit)
    except Exception as exc:
        raise AssertionError(f"{role} {ch.name}: unit {ch.unit!r} does not parse ({exc})") from None
    factor = q.to_base_units().magnitude
    assert factor == 1.0, (
        f"{role} {ch.name}: unit {ch.unit!r} is not SI (1 {ch.unit} = {factor:g} in base units)"
    )


def channels_declared(s: PlantSubject) -> None:
    p = s.plant
    assert isinstance(p.nx, int) and p.nx > 0, f"nx: must be a positive int, got {p.nx!r}"
    for role, channels in (("input", p.inputs), ("output", p.outputs)):
        assert len(channels) > 0, f"{role}s: the plant declares no {role} channel"
        names = [c.name for c in channels]
        assert all(isinstance(c, Channel) for c in channels), f"{role}s: not all Channels"
        dup = sorted({n for n in names if names.count(n) > 1})
        assert not dup, f"{role}s: channel names {dup} appear twice"
        for c in channels:
            assert isinstance(c.size, int) and c.size > 0, f"{role} {c.name}: size {c.size!r}"
            _check_unit(c, role)
    both = sorted({c.name for c in p.inputs} & {c.name for c in p.outputs})
    assert not both, f"channels {both} are both inputs and outputs (the dataset keys clash)"
    outs = {c.name: c for c in p.outputs}
    ins = {c.name: c for c in p.inputs}
    bad = [k for k in p.recorded if k not in outs]
    assert not bad, f"recorded: {bad} are not output channels"
    bad = [k for k in p.noise_channels if k not in outs and k not in ins]
    assert not bad, f"noise_channels: {bad} are not channels of the plant"
    axis = p.maneuver
    if axis is not None:
        for field, unit in MANEUVER_UNITS.items():
            name = getattr(axis, field)
            table = ins if field == "torque" else outs
            assert name in table, f"maneuver.{field}: {name!r} is not a channel of the plant"
            ch = table[name]
            assert Q_(1.0, ch.unit).to_base_units() == Q_(1.0, unit).to_base_units(), (
                f"maneuver.{field}: {name} is in {ch.unit!r}, must be {unit}"
            )
            assert ch.size == 1, f"maneuver.{field}: {name} has size {ch.size}, must be 1"
        assert unit_row(p, axis.angle) is not None, (
            f"maneuver.angle: {axis.angle} is not a state coordinate"
        )
        assert callable(getattr(p, "vibration_energy", None)), (
            "maneuver: a maneuver plant must give vibration_energy(x)"
        )


# -- shapes ---------------------------------------------------------------------------------------
def _outputs(p: Plant, x: FloatArray, u: FloatArray) -> dict[str, FloatArray]:
    return {c.name: np.asarray(p.output(c.name, x, u)) for c in p.outputs}


def shapes(s: PlantSubject) -> None:
    p = s.plant
    nx, m, pc = p.nx, p.n_inputs, p.n_cases
    A, B = p.linear_part()
    lead = () if pc == 1 else (pc,)
    assert np.shape(A) in ((nx, nx), lead + (nx, nx)), f"A: shape {np.shape(A)}, n_x = {nx}"
    assert np.shape(B) in ((nx, m), lead + (nx, m)), f"B: shape {np.shape(B)}, (n_x, m) = {nx, m}"
    Bf = p.force_matrix
    if p.nonlinear:
        assert Bf is not None, "nonlinear: the plant is nonlinear but gives no force_matrix"
        assert np.ndim(Bf) in (2, 3) and np.shape(Bf)[-2] == nx, (
            f"force_matrix: shape {np.shape(Bf)}, must be (n_x, n_f) with n_x = {nx}"
        )
    for nc in cases_of(p):
        x0 = np.asarray(p.initial_state(nc))
        assert x0.shape in ((nc, nx), (nx,)), f"initial_state({nc}): shape {x0.shape}"
        x, u = s.states(nc), s.inputs(nc)
        if p.nonlinear:
            assert Bf is not None  # asserted above for a nonlinear plant
            f = np.asarray(p.nonlinear_force(x, u))
            assert f.shape == (nc, Bf.shape[-1]), (
                f"nonlinear_force: shape {f.shape} for {nc} cases, expected {(nc, Bf.shape[-1])}"
            )
        for c in p.outputs:
            y = np.asarray(p.output(c.name, x, u))
            want = (nc,) if c.size == 1 else (nc, c.size)
            assert y.shape == want, f"output {c.name}: shape {y.shape} for {nc} cases, want {want}"
            assert np.isfinite(y).all(), f"output {c.name}: non-finite at a finite state"
        E = p.energy(x)
        if E is not None:
            assert np.shape(E) == (nc,), f"energy: shape {np.shape(E)} for {nc} cases"
        H = p.momentum(x)
        if H is not None:
            assert np.shape(H) in ((nc,), (nc, 3)), f"momentum: shape {np.shape(H)}"
        P = p.power(x, u)
        if P is not None:
            assert np.shape(P) == (nc,), f"power: shape {np.shape(P)} for {nc} cases"
    # a leading time axis: (n_t, n_cases, ...) is the stack of its time slices
    nc = cases_of(p)[-1]
    xt = np.stack([s.states(nc, 0), s.states(nc, 5)])
    ut = np.stack([s.inputs(nc, 1), s.inputs(nc, 6)])
    for c in p.outputs:
        y = np.asarray(p.output(c.name, xt, ut))
        each = np.stack([np.asarray(p.output(c.name, xt[k], ut[k])) for k in range(2)])
        assert y.shape == each.shape, f"output {c.name}: shape {y.shape} with a time axis"
        assert_close(
            f"output {c.name}",
            y,
            each,
            4 * (nx + m) * EPS * magnitude(each, xt),
            "time × case evaluation vs its slices",
        )


# -- batch_equals_singles -------------------------------------------------------------------------
def _evaluations(p: Plant, x: FloatArray, u: FloatArray) -> dict[str, FloatArray]:
    out = {f"output {k}": v for k, v in _outputs(p, x, u).items()}
    if p.nonlinear:
        out["nonlinear_force"] = p.nonlinear_force(x, u)
    for name, value in (("energy", p.energy(x)), ("power", p.power(x, u))):
        if value is not None:
            out[name] = value
    return out


def _histories(result: SimResult) -> list[str]:
    """The time histories of a run (its metrics are functions of them, compared through
    them: a metric alone has no scale for the round-off of the state it was read from)."""
    # str(k) is k: the recorder names every variable by a str (a channel or metric name)
    return [str(k) for k, v in result.dataset.data_vars.items() if "time" in v.dims]


def _compare_runs(a: SimResult, b: SimResult, bound_per_sample: float, what: str) -> None:
    assert _histories(a) == _histories(b), f"histories: {_histories(a)} vs {_histories(b)}"
    for name in _histories(a):
        va, vb = a.dataset[name].values, b.dataset[name].values
        tol = bound_per_sample * (CHECK_SAMPLES + 1) * magnitude(va, vb)
        assert_close(name, va, vb, tol, what)


def batch_equals_singles(s: PlantSubject) -> None:
    p = s.plant
    bound = 4 * (p.nx + p.n_inputs) * EPS
    x, u = s.states(3), s.inputs(3)
    batch = _evaluations(p, x, u)
    for i in range(3):
        single = _evaluations(p, x[i : i + 1], u[i : i + 1])
        for k, v in batch.items():
            assert_close(
                k, v[i : i + 1], single[k], bound * magnitude(v, x), f"case {i} of 3 vs alone"
            )
    run = s.run(p, 3)  # seed 0: case i draws from seed i
    for i in range(3):
        alone_law = HoldLaw(split_inputs(p, s.inputs(3)[i : i + 1]))
        name = s.noisy_input()
        disturbances = {} if name is None else {name: ChannelDisturbance(random=s.input_scale)}
        alone = simulate(
            p,
            alone_law,
            s.config(channel_disturbances=disturbances),
            n_cases=1,
            seeds=[i],
            initial_state=s.states(3)[i],
        )
        for k in _histories(alone):
            va = run.dataset[k].values[i : i + 1]
            vb = alone.dataset[k].values
            tol = bound * (CHECK_SAMPLES + 1) * magnitude(run.dataset[k].values, vb)
            assert_close(k, va, vb, tol, f"run: case {i} of 3 vs alone with its seed")


# -- dispersion -----------------------------------------------------------------------------------
def dispersion(s: PlantSubject) -> None:
    p = s.plant
    stacked = stack_plants([p, p, p])
    assert stacked.n_cases == 3, f"stack_plants: n_cases {stacked.n_cases}, expected 3"
    A, B = p.linear_part()
    As, Bs = stacked.linear_part()
    assert np.array_equal(As, np.stack([A] * 3)) and np.array_equal(Bs, np.stack([B] * 3)), (
        "linear_part: the stacked plant's (A, B) are not the plant's per case"
    )
    x, u = s.states(3), s.inputs(3)
    bound = 4 * (p.nx + p.n_inputs) * EPS
    want = _evaluations(p, x, u)
    got = _evaluations(stacked, x, u)
    assert set(got) == set(want), f"evaluations: {sorted(set(got) ^ set(want))} differ"
    for k in want:
        assert_close(k, got[k], want[k], bound * magnitude(want[k], x), "stacked vs batch")
    _compare_runs(s.run(stacked, 3), s.run(p, 3), bound, "run: stacked plant vs batch")


# -- linear_form ----------------------------------------------------------------------------------
def _richardson(g: Callable[[float], FloatArray], h: float) -> tuple[FloatArray, FloatArray]:
    """(g(h/2), |g(h) − g(h/2)|): a difference quotient and the bound on its error (the change
    between step h and h/2 is 3/4 of the O(h²) term at h, 3 × its value at h/2)."""
    a, b = g(h), g(h / 2)
    return b, np.abs(a - b)


def linear_form(s: PlantSubject) -> None:
    p = s.plant
    if p.nonlinear:
        assert p.force_matrix is not None, "nonlinear: True but force_matrix is None"
    nc = cases_of(p)[-1]
    x, u = s.states(nc), s.inputs(nc)
    xd = state_derivative(p, x, u)
    scale_x = magnitude(x)
    jac = p.force_jacobian(x, u) if p.nonlinear else None
    if jac is not None:
        rng = np.random.default_rng(s.seed + 7)
        dx, du = rng.standard_normal(x.shape), rng.standard_normal(u.shape)
        h = 1e-3 * scale_x
        for name, J, d, shift in (
            ("force_jacobian ∂f/∂x", jac[0], dx, lambda e: (x + e * dx, u)),
            ("force_jacobian ∂f/∂u", jac[1], du, lambda e: (x, u + e * du)),
        ):

            def quotient(
                e: float, shift: Callable[[float], tuple[FloatArray, FloatArray]] = shift
            ) -> FloatArray:
                return (p.nonlinear_force(*shift(e)) - p.nonlinear_force(*shift(-e))) / (2 * e)

            fd, err = _richardson(quotient, h)
            f0 = magnitude(p.nonlinear_force(x, u))
            tol = 3 * err + 16 * p.nx * EPS * f0 / h + 1e-12 * magnitude(fd)
            assert_close(name, matvec(J, d), fd, tol.max(), "analytic vs central difference")
    own_step = p.step
    if own_step is not None:
        h = 1e-3 * scale_x / magnitude(xd)

        def step_quotient(e: float) -> FloatArray:
            return (np.asarray(own_step(x, u, e)) - x) / e

        def extrapolated(e: float) -> FloatArray:
            return 2 * step_quotient(e / 2) - step_quotient(e)

        r, err = _richardson(extrapolated, h)
        tol = 3 * err.max() + 64 * EPS * scale_x / h
        assert_close("step", r, xd, tol, "(step(x, u, h) − x)/h extrapolated vs A x + B u + B_f f")
    for name in ("rhs", "derivative"):
        method = getattr(p, name, None)
        if callable(method):
            assert_close(
                name,
                method(x, u),
                xd,
                8 * (p.nx + p.n_inputs) * EPS * magnitude(xd, x) * magnitude(p.linear_part()[0]),
                "the plant's own derivative vs A x + B u + B_f f",
            )
    # the matrices of a dispersed plant carry a case axis the protocol's own evaluation
    # (Plant.output) does not take: the engine applies them, checked by ``dispersion``
    for c in p.outputs if p.n_cases == 1 else ():
        mats = p.output_matrices(c.name)
        if mats is not None and type(p).output is not Plant.output:
            assert_close(
                f"output {c.name}",
                Plant.output(p, c.name, x, u),
                p.output(c.name, x, u),
                8 * (p.nx + p.n_inputs) * EPS * magnitude(x, u) * magnitude(*mats[:2]),
                "output_matrices vs output()",
            )


# -- energy ---------------------------------------------------------------------------------------
def _rate(
    quantity: Callable[[FloatArray], FloatArray | None], x: FloatArray, xd: FloatArray, h: float
) -> tuple[FloatArray, FloatArray]:
    """Central difference of ``quantity`` along x' and its error bound (Richardson +
    round-off)."""

    def fun(z: FloatArray) -> FloatArray:
        # a quantity the plant defines: the energy check is skipped for a plant whose energy is
        # None, and momentum is differenced only when it is not None
        value = quantity(z)
        assert value is not None, "the differenced quantity is None"
        return value

    d, err = _richardson(lambda e: (fun(x + e * xd) - fun(x - e * xd)) / (2 * e), h)
    roundoff = 16 * x.shape[-1] * EPS * magnitude(fun(x + h * xd), fun(x)) / h
    return d, 3 * err + roundoff


def energy(s: PlantSubject) -> None:
    p = s.plant
    nc = cases_of(p)[-1]
    x, u = s.states(nc), s.inputs(nc)
    zero = np.zeros_like(u)
    for drive, uu in (("free motion", zero), ("driven", u)):
        xd = state_derivative(p, x, uu)
        h = 1e-4 * magnitude(x) / magnitude(xd)
        dE, tol = _rate(p.energy, x, xd, h)
        power = p.power(x, uu)
        if power is not None:
            assert_close(
                "power",
                power,
                dE,
                tol + 8 * p.nx * EPS * magnitude(power),
                f"declared dE/dt vs ∇E·x' ({drive})",
            )
        elif drive == "free motion":
            assert (dE <= tol).all(), (
                f"energy: grows in free motion, dE/dt = {dE.max():.3g} > {tol.max():.3g} "
                "(a passive plant's energy cannot grow without input)"
            )
        if drive == "free motion" and p.momentum(x) is not None:
            dH, tolH = _rate(p.momentum, x, xd, h)
            tolH = np.broadcast_to(
                tolH if np.ndim(tolH) == np.ndim(dH) else tolH[..., None], dH.shape
            )
            assert (np.abs(dH) <= tolH).all(), (
                f"momentum: changes in free motion, |dH/dt| = {np.abs(dH).max():.3g} > "
                f"{tolH.max():.3g}"
            )
    Q = p.energy_matrix
    if Q is not None:
        Q = np.asarray(Q)
        quad = 0.5 * np.einsum("...i,...ij,...j->...", x, Q, x)
        energy = p.energy(x)
        # a plant declares an energy matrix only for an energy it defines (Plant.energy_matrix)
        assert energy is not None, "energy_matrix: given, but energy(x) is None"
        assert_close(
            "energy_matrix",
            quad,
            energy,
            4 * p.nx * EPS * magnitude(Q) * magnitude(x) ** 2,
            "½ xᵀ Q x vs energy(x)",
        )


# -- determinism ----------------------------------------------------------------------------------
def determinism(s: PlantSubject) -> None:
    p = s.plant
    nc = cases_of(p)[-1]
    a, b = s.run(p, nc, seed=5), s.run(p, nc, seed=5)
    for name in a.dataset.data_vars:
        va, vb = a.dataset[name].values, b.dataset[name].values
        assert np.array_equal(va, vb, equal_nan=True), f"{name}: two runs with seed 5 differ"
    if s.noisy_input() is not None:
        c = s.run(p, nc, seed=6)
        assert any(
            not np.array_equal(a.dataset[k].values, c.dataset[k].values, equal_nan=True)
            for k in a.dataset.data_vars
        ), "seed: runs with seeds 5 and 6 are identical (the random disturbance is not drawn)"


# -- bad_input ------------------------------------------------------------------------------------
def _refused(field: str, action: Callable[[], object], what: str) -> None:
    try:
        action()
    except ValueError as exc:
        assert field in str(exc), f"{what}: the ValueError does not name {field!r}: {exc}"
        return
    raise AssertionError(f"{what}: accepted (expected a ValueError naming {field!r})")


def bad_input(s: PlantSubject) -> None:
    p = s.plant
    nc = cases_of(p)[-1]
    x, u = s.states(nc), s.inputs(nc)
    _refused("no_such_channel", lambda: p.output("no_such_channel", x, u), "an unknown output")
    _refused("no_such_value", lambda: p.state_from(no_such_value=1.0), "an unknown initial value")
    _refused("state", lambda: p.state_from(state=np.full(p.nx, np.nan)), "a NaN initial state")
    _refused("state", lambda: p.state_from(state=np.zeros(p.nx + 1)), "a misshapen state")
    rest = np.atleast_2d(p.initial_state(nc))[0]
    try:
        p.state_from(state=rest)
    except ValueError as exc:
        raise AssertionError(
            f"initial_state: the plant's own rest state (what simulate starts from) is refused "
            f"by state_from: {exc}"
        ) from None
    law = HoldLaw(split_inputs(p, u))
    config = s.config()
    for bad, what in (
        (np.full((nc, p.nx), np.nan), "a NaN initial_state"),
        (np.zeros((nc, p.nx + 1)), "a misshapen initial_state"),
    ):
        _refused(
            "initial_state",
            functools.partial(simulate, p, law, config, n_cases=nc, initial_state=bad),
            what,
        )
    wrong = HoldLaw({"no_such_input": np.zeros(nc)})
    _refused("no_such_input", lambda: check_law(p, wrong), "a law writing an unknown channel")


PLANT_CHECKS = (
    channels_declared,
    shapes,
    batch_equals_singles,
    dispersion,
    linear_form,
    energy,
    determinism,
    bad_input,
)


def _skip(s: PlantSubject, name: str) -> str | None:
    """Why check ``name`` does not apply, from the plant's declarations (None: it applies)."""
    p = s.plant
    if name == "dispersion":
        if p.step is not None and getattr(type(p), "stacked", None) is None:
            return "the plant has its own integrator (step), which stack_plants refuses"
        if p.n_cases != 1:
            return "the plant is already dispersed"
    if name == "batch_equals_singles" and p.n_cases != 1:
        return "a dispersed plant's cases are not single plants"
    if name == "energy" and p.energy(s.states(cases_of(p)[-1])) is None:
        return "the plant declares no energy (energy() is None)"
    return None


def plant_checks(
    plant: Plant,
    *,
    state_scale: float = 1e-2,
    input_scale: float = 1e-3,
    seed: int = 0,
    rest_state: npt.ArrayLike | None = None,
) -> list[Check]:
    """The conformance checks of ``plant`` (module docstring), each with its skip reason.

    Parameters
    ----------
    plant : Plant
    state_scale, input_scale : float
        1σ of the sample state perturbation about rest and of the sample inputs, SI: small
        enough for the plant's linear range, large enough to be well above round-off.
    seed : int
        Seed of the samples.
    rest_state : array (n_x,), optional
        The state the samples perturb (default the plant's ``initial_state``), SI.

    Returns
    -------
    list of :class:`~flexsat.testing.checks.Check`
    """
    s = PlantSubject(plant, state_scale, input_scale, seed, rest_state)
    out: list[Check] = []
    for fn in PLANT_CHECKS:
        skip = _skip(s, fn.__name__)
        out.append(Check(s.name, fn.__name__, functools.partial(fn, s), skip))
    return out


__all__ = ["PLANT_CHECKS", "PlantSubject", "plant_checks"]
