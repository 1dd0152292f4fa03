"""Bad input to the Creamer-Junkins identification API is refused by name: the checks of
:mod:`flexsat.identify.structural.validation` and those of each entry point.  Input is
refused: every call below raises a :class:`~flexsat.input_checks.FieldError` whose
field is the parameter at fault (never a numpy traceback, a hang or NaN).

The model is the 3-dof ``chain`` of tests/identify/conftest.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat import limits
from flexsat.identify.structural import (
    SubstructureModel,
    damped_eigenvalues,
    fit_modal_normalization,
    identify_damping,
    identify_undamped,
    modal_energy_distribution,
    substructures_from_builder,
    update_model,
)
from flexsat.input_checks import FieldError
from flexsat.units import Q_
from param_ids import stable_id

NAN, INF = np.nan, np.inf
#: values that are no matrix of numbers
NOT_A_MATRIX = [NAN, INF, "abc", Q_(1.0, "m"), np.ones(3), np.ones((2, 2, 2)), np.zeros((0, 0))]
#: values that are no vector of positive frequencies (rad/s)
NOT_FREQUENCIES = [NAN, INF, [], "abc", Q_(1.0, "m"), -1.0, 0.0, np.ones((2, 2, 2))]
#: values that are no index list of one of 3 blocks
NOT_INDICES = [[5], [-1], [0.5], "a", [True]]


def _blocks(chain):
    return chain.K_blocks, chain.M_blocks


def _frf(chain):
    """A receptance element (0, 0) of the chain at 4 points away from its resonances."""
    w = np.array([5.0, 15.0, 60.0, 100.0])
    h = np.array([np.linalg.solve(chain.K() - x**2 * chain.M(), np.eye(3)[0])[0] for x in w])
    return (0, 0, w, h)


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize("bad", NOT_A_MATRIX, ids=stable_id)
@pytest.mark.parametrize("which", ["K_blocks", "M_blocks", "C_blocks", "K0"])
def test_substructure_model_refuses_a_bad_matrix(chain, which, bad):
    Kb, Mb = _blocks(chain)
    given = {"K_blocks": Kb, "M_blocks": Mb}
    given[which] = bad if which == "K0" else [bad]
    _raises(which, lambda: SubstructureModel(**given))


@pytest.mark.parametrize(
    "field, changes",
    [
        ("K_blocks", {"K_blocks": []}),
        ("K_blocks", {"K_blocks": None}),
        ("K_blocks", {"K_blocks": 5}),
        ("K_blocks", {"K_blocks": np.eye(3)}),  # one matrix, not a list of blocks
        ("K_blocks", {"K_blocks": np.stack([np.eye(3)] * 3)}),
        ("K_blocks[0]", {"K_blocks": [np.eye(3) + np.triu(np.ones((3, 3)), 1)]}),  # asymmetric
        ("M_blocks", {"M_blocks": []}),
        ("M_blocks[0]", {"M_blocks": [np.ones((3, 2))]}),
        ("M_blocks[0]", {"M_blocks": [np.eye(4)]}),  # not the size of the K blocks
        ("names", {"names": 5}),
        ("names", {"names": [1, 2, 3]}),
    ],
    ids=stable_id,
)
def test_substructure_model_refuses_bad_lists(chain, field, changes):
    Kb, Mb = _blocks(chain)
    _raises(field, lambda: SubstructureModel(**{"K_blocks": Kb, "M_blocks": Mb, **changes}))


@pytest.mark.parametrize("bad", [NAN, INF, "abc", Q_(1.0, "m"), 1 + 1j, [1.0, 1.0]], ids=stable_id)
@pytest.mark.parametrize("method, field", [("K", "p"), ("M", "q"), ("C", "r")])
def test_scalings_refused_by_name(chain, method, field, bad):
    value = bad if np.ndim(bad) else [bad] * 3
    _raises(field, lambda: getattr(chain, method)(value))


@pytest.mark.parametrize(
    "field, kwargs",
    [
        ("q", {"q": [-1.0, 1.0, 1.0]}),  # M(q) indefinite
        ("p", {"p": [-1.0, 1.0, 1.0]}),  # K(p) indefinite
        ("n_modes", {"n_modes": 0}),
        ("n_modes", {"n_modes": -3}),
        ("n_modes", {"n_modes": NAN}),
        ("n_modes", {"n_modes": 1.5}),
        ("n_modes", {"n_modes": [1, 2]}),
    ],
    ids=stable_id,
)
def test_modes_refuses_by_name(chain, field, kwargs):
    _raises(field, lambda: chain.modes(**kwargs))


def test_indefinite_blocks_refused_at_the_modes(chain):
    Kb, Mb = _blocks(chain)
    _raises("q", SubstructureModel(Kb, [-M for M in Mb]).modes)
    _raises("p", SubstructureModel([-K for K in Kb], Mb).modes)


# ------------------------------------------------------------------------------------------------
class _Assembly:
    def __init__(self, K, M):
        self.K, self.M = K, M


def _unit(k, m):
    return _Assembly(np.eye(3) * (1 + k.sum()), np.eye(3) * (1 + m.sum()))


@pytest.mark.parametrize(
    "field, args",
    [
        ("build", (None, 3)),
        ("n_stiffness", (_unit, -1)),
        ("n_stiffness", (_unit, 0)),
        ("n_stiffness", (_unit, NAN)),
        ("n_stiffness", (_unit, True)),
        ("n_stiffness", (_unit, 10**12)),  # refused before np.ones(10**12)
        ("n_mass", (_unit, 1, -2)),
        ("n_mass", (_unit, 1, 0.5)),
        ("n_mass", (_unit, 1, True)),
        ("build", (lambda k, m: 5, 2)),
        ("build().K", (lambda k, m: _Assembly(np.full((3, 3), NAN), np.eye(3)), 2)),
        ("build().M", (lambda k, m: _Assembly(np.eye(3), np.eye(2)), 2)),
    ],
    ids=stable_id,
)
def test_substructures_from_builder_refuses_by_name(field, args):
    _raises(field, lambda: substructures_from_builder(*args))


def test_substructures_from_builder_may_hold_the_whole_mass_fixed():
    """n_mass = 0: no mass block, the mass in M0 (the identification scenario's clamp)."""
    model = substructures_from_builder(_unit, 1, 0)
    assert model.n_mass == 0 and np.allclose(model.M0, np.eye(3))


def test_substructures_from_builder_limit_is_the_element_limit():
    """More substructures than a case may have elements is refused, naming the limit."""
    with pytest.raises(FieldError, match=r"n_stiffness: .*above the limit 1,000"):
        substructures_from_builder(_unit, limits.MAX_ELEMENTS + 1, 0 + 1)


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "field, call",
    [
        *[
            ("shapes", lambda c, b=b: modal_energy_distribution(*_blocks(c), b))
            for b in NOT_A_MATRIX[:4]
        ],
        ("shapes", lambda c: modal_energy_distribution(*_blocks(c), [])),
        ("shapes", lambda c: modal_energy_distribution(*_blocks(c), np.ones((4, 2)))),
        ("shapes", lambda c: modal_energy_distribution(*_blocks(c), np.zeros((3, 2)))),
        ("omegas", lambda c: modal_energy_distribution(*_blocks(c), c.modes()[1], -c.modes()[0])),
        ("omegas", lambda c: modal_energy_distribution(*_blocks(c), c.modes()[1], [NAN] * 3)),
        ("omegas", lambda c: modal_energy_distribution(*_blocks(c), c.modes()[1], Q_(1, "m"))),
        ("omegas", lambda c: modal_energy_distribution(*_blocks(c), c.modes()[1], [1.0])),
        ("K_blocks", lambda c: modal_energy_distribution([], c.M_blocks, c.modes()[1])),
        ("M_blocks", lambda c: modal_energy_distribution(c.K_blocks, [], c.modes()[1])),
    ],
)
def test_modal_energy_distribution_refuses_by_name(chain, field, call):
    _raises(field, lambda: call(chain))


def _fit(chain, **changes):
    w, phi = chain.modes()
    given = {"frf": _frf(chain), "shapes": phi, "omegas": w, **changes}
    return fit_modal_normalization(**given)


@pytest.mark.parametrize(
    "field, changes",
    [
        # (a vector is one shape: then the 3 omegas are refused, tested below)
        *[("shapes", {"shapes": b}) for b in NOT_A_MATRIX if np.ndim(b) != 1],
        *[("omegas", {"omegas": b}) for b in NOT_FREQUENCIES],
        ("omegas", {"omegas": [10.0, 20.0]}),  # one per shape
        ("frf", {"frf": None}),
        ("frf", {"frf": []}),
        ("frf", {"frf": 5}),
        ("frf[0].output_dof", {"frf": (9, 0, [5.0, 15.0], [1.0, 2.0])}),
        ("frf[0].values", {"frf": (0, 0, [5.0, 15.0], [NAN, 2.0])}),
        ("known_part", {"known_part": []}),
        ("known_part[0]", {"known_part": [np.full(4, NAN)]}),
        ("known_part[0]", {"known_part": [np.ones(2)]}),
    ],
    ids=stable_id,
)
def test_fit_modal_normalization_refuses_by_name(chain, field, changes):
    _raises(field, lambda: _fit(chain, **changes))


# ------------------------------------------------------------------------------------------------
def _undamped(chain, **changes):
    given = {"model": chain, "measured_frequencies": chain.modes()[0], **changes}
    return identify_undamped(**given)


@pytest.mark.parametrize(
    "field, changes",
    [
        *[("measured_frequencies", {"measured_frequencies": b}) for b in NOT_FREQUENCIES],
        ("measured_frequencies", {"measured_frequencies": np.arange(1.0, 6.0)}),  # > dofs
        ("model", {"model": None}),
        ("model", {"model": "abc"}),
        *[("measured_shapes", {"measured_shapes": b}) for b in NOT_A_MATRIX[:5]],
        ("measured_shapes", {"measured_shapes": np.zeros((3, 3))}),  # was: SVD did not converge
        ("p0", {"p0": [NAN] * 3}),
        ("p0", {"p0": [-1.0, 1.0, 1.0]}),
        ("p0", {"p0": [0.0] * 3}),
        ("q0", {"q0": [-1.0, 1.0, 1.0]}),
        *[("fixed_stiffness", {"fixed_stiffness": b}) for b in NOT_INDICES],
        ("fixed_stiffness", {"fixed_stiffness": [0, 1, 2]}),  # nothing left to identify
        ("frequency_sigma", {"frequency_sigma": NAN}),
        ("frequency_sigma", {"frequency_sigma": -1.0}),
        ("frequency_sigma", {"frequency_sigma": [1.0, 2.0]}),
        ("frequency_sigma", {"frequency_sigma": Q_(1.0, "m")}),
        ("frf_sigma", {"frf_sigma": NAN}),
        ("frf_sigma", {"frf_sigma": -1.0}),
        ("frf_sigma", {"frf_sigma": "x"}),
        ("mode_indices", {"mode_indices": [9, 9, 9]}),
        ("mode_indices", {"mode_indices": [-1, 0, 1]}),
        ("mode_indices", {"mode_indices": [0, 0, 0]}),
        ("mode_indices", {"mode_indices": [0]}),
        ("mode_indices", {"mode_indices": [NAN] * 3}),
        ("n_iter", {"n_iter": 0}),
        ("n_iter", {"n_iter": -5}),
        ("n_iter", {"n_iter": NAN}),
        ("n_iter", {"n_iter": limits.MAX_FIT_ITERATIONS + 1}),  # was: runs for ever with tol=0
        ("tol", {"tol": NAN}),
        ("tol", {"tol": -1.0}),
        ("tol", {"tol": "x"}),
        ("identify_mass", {"identify_mass": True}),  # the mass needs an FRF
    ],
    ids=stable_id,
)
def test_identify_undamped_refuses_by_name(chain, field, changes):
    _raises(field, lambda: _undamped(chain, **changes))


def test_identify_undamped_frf_sigma_and_prior_refused_by_name(chain):
    frf = _frf(chain)
    _raises("frf_sigma", lambda: _undamped(chain, frf=frf, frf_sigma=NAN))
    _raises(
        "mass_prior_sigma",
        lambda: _undamped(chain, frf=frf, frf_sigma=0.01, mass_prior_sigma=INF),
    )


def _eigenvalues(chain):
    return damped_eigenvalues(chain.K(), chain.M(), chain.C())


@pytest.mark.parametrize(
    "field, changes",
    [
        *[
            ("measured_eigenvalues", {"measured_eigenvalues": b})
            for b in (NAN, INF, [], "abc", Q_(1.0, "m"), 0.0, np.ones((2, 2, 2)))
        ],
        ("model", {"model": None}),
        ("p", {"p": [NAN] * 3}),
        ("p", {"p": [-1.0] * 3}),
        ("q", {"q": [-1.0] * 3}),
        ("r0", {"r0": [INF] * 3}),
        *[("fixed", {"fixed": b}) for b in NOT_INDICES],
        ("mode_indices", {"mode_indices": [NAN] * 3}),
        ("mode_indices", {"mode_indices": []}),
    ],
    ids=stable_id,
)
def test_identify_damping_refuses_by_name(chain, field, changes):
    given = {"model": chain, "measured_eigenvalues": _eigenvalues(chain), **changes}
    _raises(field, lambda: identify_damping(**given))


def test_identify_damping_refuses_unstable_eigenvalues_and_no_damping_blocks(chain):
    lam = _eigenvalues(chain)
    _raises("measured_eigenvalues", lambda: identify_damping(chain, -lam.conj()))
    _raises("C_blocks", lambda: identify_damping(SubstructureModel(*_blocks(chain)), lam))


@pytest.mark.parametrize(
    "field, args",
    [
        ("M", lambda c: (c.K(), np.zeros((3, 3)), c.C())),  # was: LinAlgError, singular
        ("K", lambda c: (np.full((3, 3), NAN), c.M(), c.C())),
        ("C", lambda c: (c.K(), c.M(), np.eye(2))),
        ("K", lambda c: ("abc", c.M(), c.C())),
        ("K", lambda c: ([], [], [])),
        ("n_modes", lambda c: (c.K(), c.M(), c.C(), -1)),  # was: lam[:-1], silently
        ("n_modes", lambda c: (c.K(), c.M(), c.C(), NAN)),
    ],
)
def test_damped_eigenvalues_refuses_by_name(chain, field, args):
    _raises(field, lambda: damped_eigenvalues(*args(chain)))


def test_update_model_refuses_by_name(chain):
    w = chain.modes()[0]
    _raises("measured_frequencies", lambda: update_model(chain, [NAN]))
    _raises("measured_eigenvalues", lambda: update_model(chain, w, [NAN]))
    _raises("damping_kwargs", lambda: update_model(chain, w, _eigenvalues(chain), damping_kwargs=5))


def test_valid_inputs_still_identify_the_chain(chain):
    """The checks refuse only what they should: the exact data give the nominal scalings
    (undamped to 1e-8, the first-order damping to its 1 % stiffness-proportional level)."""
    w = chain.modes()[0]
    res = update_model(chain, Q_(w / (2 * np.pi), "Hz"), _eigenvalues(chain), frf=_frf(chain))
    assert np.allclose(res.p, 1.0, atol=1e-8) and np.allclose(res.q, 1.0, atol=1e-8)
    assert np.allclose(res.r, 1.0, atol=0.05)


# ------------------------------------------------------------------------------------------------
def test_degenerate_inputs_raise_clear_errors(frame):
    w, _ = frame.modes()
    with pytest.raises(ValueError, match="more parameters than data"):
        identify_undamped(frame, w[:2])
    with pytest.raises(ValueError, match="measured_frequencies: must be finite"):
        identify_undamped(frame, [w[0], np.nan, w[2]])
    with pytest.raises(ValueError, match="measured_frequencies"):
        identify_undamped(frame, [-1.0, 2.0, 3.0])
    with pytest.raises(ValueError, match="measured_shapes: must have shape"):
        identify_undamped(frame, w[:4], measured_shapes=np.ones((3, 4)))
    with pytest.raises(ValueError, match="identify_mass"):
        identify_undamped(frame, w[:4], identify_mass=True)
    with pytest.raises(ValueError, match="C_blocks"):
        identify_damping(frame, [-0.1 + 1j])
    damped = SubstructureModel(frame.K_blocks, frame.M_blocks, [frame.M(), frame.K()])
    with pytest.raises(ValueError, match="more parameters than data"):
        identify_damping(damped, [-0.1 + 1j * w[0]])
    with pytest.raises(ValueError, match="no NaN"):
        identify_damping(damped, [np.nan, -0.1])
    with pytest.raises(ValueError, match="real parts must be < 0"):
        identify_damping(damped, [0.1 + 1j, -0.1 + 2j])
    with pytest.raises(ValueError, match=r"K_blocks\[1\]: must be symmetric"):
        SubstructureModel([frame.K_blocks[0], np.triu(frame.K_blocks[1])], frame.M_blocks)
    with pytest.raises(ValueError, match="p: must have 3 entries"):
        frame.K([1.0, 2.0])
    with pytest.raises(ValueError, match="mass scalings: M\\(q\\) is not positive definite"):
        frame.modes(q=[-1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="stiffness scalings: K\\(p\\) is not positive semi-"):
        frame.modes(p=[-1.0, 1.0, 1.0])
    with pytest.raises(ValueError, match="n_modes: must be a positive integer"):
        frame.modes(n_modes=0)
    with pytest.raises(ValueError, match="frf"):
        identify_undamped(frame, w[:4], frf=[(0, 0, [1.0], [1.0, 2.0])])
