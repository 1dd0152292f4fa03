"""One engine: nothing outside ``src/flexsat/sim`` integrates dynamics in time.

flexsat's rule (issue 20): anything with dynamics runs through :func:`flexsat.sim.simulate` (its
sampled mode, or the continuous-law mode of :mod:`flexsat.sim.continuous`); a new system is a new
plant, never a second integration loop. Every function under ``src/flexsat`` is parsed with
:mod:`ast` (nothing is imported) and flagged when it

* calls an ODE solver (``solve_ivp``, ``odeint``, ``ode``, ``RK45``, ``DOP853``, ``solve_bvp``,
  scipy.signal's ``lsim``/``dlsim``, python-control's ``forced_response`` ...) or passes such a
  solver as ``method=``;
* computes a matrix exponential and multiplies matrices inside a loop (an expm-stepping loop);
* assigns the four stages ``k1`` ... ``k4`` of a Runge-Kutta step (any suffix: ``k1t``,
  ``k1w``);
* calls one of the functions above inside a loop (a time loop over a one-step kernel).

Each flagged function outside ``sim/`` must be in :data:`ALLOWED` with the reason it is not a
time integration of a system's dynamics. The detector is itself tested on snippets of each
pattern, so a pattern it stopped seeing fails here.
"""

from __future__ import annotations

import ast
import re
from functools import cache
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "flexsat"

SOLVERS = {
    "solve_ivp",
    "odeint",
    "ode",
    "complex_ode",
    "RK45",
    "RK23",
    "DOP853",
    "Radau",
    "BDF",
    "LSODA",
    "solve_bvp",
    "lsim",
    "lsim2",
    "dlsim",
    "forced_response",
    "initial_response",
}

#: (module path under src/flexsat, function) -> why it is not a time integration of dynamics
ALLOWED = {
    ("cases/tamu_codesign.py", "decay_rates"): (
        "the spectrum of each design's sampled closed-loop map (one zero-order-hold exponential "
        "per design, then its eigenvalues): a stability analysis, no trajectory"
    ),
    ("analysis/gramians.py", "finite_horizon_gramian"): (
        "a matrix integral, W(T) = ∫ e^{Ft} Q e^{Fᵀt} dt, by squaring and doubling (Van "
        "Loan's exponential of a block matrix): no trajectory of a system"
    ),
    ("maneuvers/three_axis_slew.py", "rk4"): (
        "the optimal slew's two-point boundary-value problem (state and costate, necessary "
        "conditions) by multiple shooting: RK4 gives the segment maps and their exact "
        "sensitivities for Newton; a solution of the optimality conditions, not a simulation"
    ),
    ("maneuvers/three_axis_slew.py", "dop853"): (
        "the same boundary-value problem's residuals at rtol 1e-13 (the polish of the shooting "
        "solution); its dense output is the optimal reference trajectory the laws then track"
    ),
    ("maneuvers/three_axis_slew.py", "_newton"): "the shooting Newton iteration over rk4 above",
    ("maneuvers/three_axis_slew.py", "_polish"): "the shooting polish over dop853 above",
    ("design/slew_shaping.py", "terminal_map"): (
        "the sensitivity of the terminal state to the torque-shaping coefficients (a design "
        "gradient: the variational equation of the linearisation along the nominal, one column "
        "per basis function), not a response of the plant; the plant itself runs on the engine "
        "(simulate) in the same function"
    ),
    ("design/planned_slew.py", "planned_slew"): (
        "Newton iterations of the planned slew's terminal conditions (a loop over design "
        "steps, each flying the plan on the engine and calling terminal_map), not a time loop"
    ),
    ("dynamics/rigid_body.py", "rkmk4_step"): (
        "the one-step map of a rigid body's (β, ω) on the quaternion manifold: the kernel of "
        "the plants' own step (RigidSpacecraft.step, CmgSpacecraft.step), which only the "
        "engine calls, once per substep"
    ),
}

#: flagged functions that are time integrations still to be moved onto the engine: each a
#: known gap, listed so that it is seen; the list may only shrink
PENDING: dict[tuple[str, str], str] = {}


def _name(node) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _assigned(nodes: list) -> set[str]:
    names = set()
    for node in nodes:
        targets = node.targets if isinstance(node, ast.Assign) else []
        for target in targets:
            names |= {n.id for n in ast.walk(target) if isinstance(n, ast.Name)}
    return names


def _reasons(fn, nodes: list) -> set[str]:
    """Why ``fn`` (its nodes ``nodes``) looks like a time integration (module docstring),
    without its callees."""
    why = set()
    calls = [n for n in nodes if isinstance(n, ast.Call)]
    for call in calls:
        if _name(call.func) in SOLVERS:
            why.add(f"calls {_name(call.func)}")
        for kw in call.keywords:
            if kw.arg == "method" and isinstance(kw.value, ast.Constant):
                if kw.value.value in SOLVERS:
                    why.add(f"method={kw.value.value}")
    loops = [n for n in nodes if isinstance(n, (ast.For, ast.While))]
    if not calls and not loops:
        return why
    products = any(
        isinstance(b, ast.BinOp) and isinstance(b.op, ast.MatMult)
        for loop in loops
        for b in ast.walk(loop)
    )
    if products and any(_name(c.func) == "expm" for c in calls):
        why.add("expm and matrix products in a loop")
    stages = {m.group(1) for name in _assigned(nodes) if (m := re.match(r"k([1-4])", name))}
    if stages == {"1", "2", "3", "4"}:
        why.add("Runge-Kutta stages k1..k4")
    return why


def integrators(sources: dict[str, str]) -> dict[tuple[str, str], set[str]]:
    """{(module, function): reasons} of every flagged function of ``sources`` (path -> text)."""
    functions = []
    for path, text in sources.items():
        tree = ast.parse(text)
        functions += [
            (path, fn, list(ast.walk(fn)))
            for fn in ast.walk(tree)
            if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef))
        ]
    found = {(path, fn.name): why for path, fn, nodes in functions if (why := _reasons(fn, nodes))}
    kernels = {name for _, name in found}
    for path, fn, nodes in functions:
        loops = [n for n in nodes if isinstance(n, (ast.For, ast.While))]
        called = {
            _name(c.func) for loop in loops for c in ast.walk(loop) if isinstance(c, ast.Call)
        }
        hits = (called & kernels) - {fn.name}
        if hits and (path, fn.name) not in found:
            found[(path, fn.name)] = {f"a loop over {sorted(hits)[0]}"}
    return found


@cache
def _found() -> dict[tuple[str, str], set[str]]:
    """The flagged functions of the source tree (parsed once per session)."""
    return integrators(
        {p.relative_to(SRC).as_posix(): p.read_text() for p in sorted(SRC.rglob("*.py"))}
    )


def test_no_time_integration_outside_the_engine():
    outside = {k: v for k, v in _found().items() if not k[0].startswith("sim/")}
    unexplained = {k: v for k, v in outside.items() if k not in ALLOWED and k not in PENDING}
    assert not unexplained, (
        "time integration outside src/flexsat/sim (run the system as a plant through "
        f"flexsat.sim.simulate instead): {unexplained}"
    )


def test_every_exception_still_exists_and_says_why():
    found = _found()
    for key, reason in {**ALLOWED, **PENDING}.items():
        assert key in found, f"{key}: no longer flagged: drop it from the list"
        assert len(reason) > 20


def test_the_engine_itself_is_seen():
    # the detector finds the engine's own integrators: it is looking at the right things
    found = _found()
    assert ("sim/continuous.py", "run") in found


@pytest.mark.parametrize(
    "snippet",
    [
        "from scipy.integrate import solve_ivp\ndef f(r):\n    return solve_ivp(r, (0, 1), [0])",
        "import scipy.integrate as si\ndef f(r):\n    return si.odeint(r, [0], [0, 1])",
        "def f(r, y0):\n    return integrator(r, y0, method='DOP853')",
        (
            "from scipy.linalg import expm\ndef f(A, x, n):\n    E = expm(A)\n"
            "    for _ in range(n):\n        x = E @ x\n    return x"
        ),
        (
            "def f(r, x, h):\n    k1 = r(x)\n    k2 = r(x + h / 2 * k1)\n"
            "    k3 = r(x + h / 2 * k2)\n    k4 = r(x + h * k3)\n"
            "    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)"
        ),
        (
            "def step(r, x, h):\n    k1t, k1w = r(x)\n    k2t, k2w = r(x)\n    k3t, k3w = r(x)\n"
            "    k4t, k4w = r(x)\n    return x\n"
            "def g(r, x, n):\n    for _ in range(n):\n        x = step(r, x, 0.1)\n    return x"
        ),
    ],
)
def test_the_detector_sees_each_pattern(snippet):
    found = integrators({"dynamics/example.py": snippet})
    assert found and all(k[0] == "dynamics/example.py" for k in found)


def test_the_detector_sees_a_time_loop_over_a_kernel():
    snippet = (
        "def step(r, x, h):\n    k1 = r(x)\n    k2 = r(x)\n    k3 = r(x)\n    k4 = r(x)\n"
        "    return x + h * (k1 + k2 + k3 + k4) / 4\n"
        "def run(r, x, n):\n    for _ in range(n):\n        x = step(r, x, 0.1)\n    return x"
    )
    assert set(integrators({"cases/example.py": snippet})) == {
        ("cases/example.py", "step"),
        ("cases/example.py", "run"),
    }


def test_plain_matrix_algebra_is_not_flagged():
    snippet = (
        "from scipy.linalg import expm\ndef f(A, h):\n    return expm(A * h)\n"
        "def g(M, xs):\n    return [M @ x for x in xs]"
    )
    assert integrators({"analysis/example.py": snippet}) == {}
