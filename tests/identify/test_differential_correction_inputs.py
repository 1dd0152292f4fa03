"""Bad input to the Att. 6 differential correction (:mod:`flexsat.identify.differential_correction`)
is refused by name: every call below raises a :class:`~flexsat.input_checks.FieldError` whose
field is the parameter at fault (never a numpy traceback, a hang or NaN).

The model is the 3-dof ``chain`` of tests/identify/conftest.py.
"""

from __future__ import annotations

import numpy as np
import pytest

from flexsat import limits
from flexsat.identify.differential_correction import CorrectionData, differential_correction
from flexsat.identify.structural import SubstructureModel, damped_eigenvalues
from flexsat.input_checks import FieldError
from flexsat.units import Q_
from param_ids import stable_id

NAN, INF = np.nan, np.inf
#: values that are no vector of positive numbers
NOT_POSITIVE = [NAN, INF, [], "abc", Q_(1.0, "m"), -1.0, 0.0, np.ones((2, 2, 2))]
OMEGAS = np.array([5.0, 20.0, 60.0])


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


def _frf(chain):
    """Receptance (0, 0) of the chain at OMEGAS, complex, damped."""
    K, M, C = chain.K(), chain.M(), chain.C()
    return np.array([np.linalg.solve(K - w**2 * M + 1j * w * C, np.eye(3)[0])[0] for w in OMEGAS])


@pytest.fixture(scope="module")
def data(chain):
    """Frequencies, damping ratios and one FRF of the nominal chain: 12 measurements."""
    w = chain.modes()[0]
    lam = damped_eigenvalues(chain.K(), chain.M(), chain.C())
    return CorrectionData(
        frequencies=w,
        frequency_sigma=0.01,
        damping_ratios=-lam.real / np.abs(lam),
        damping_sigma=0.01,
        frf=[(0, 0, OMEGAS, _frf(chain), 0.01)],
    )


# ------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "field, kwargs",
    [
        *[("frequencies", {"frequencies": b, "frequency_sigma": 0.1}) for b in NOT_POSITIVE],
        *[
            ("frequency_sigma", {"frequencies": [10.0, 20.0], "frequency_sigma": b})
            for b in NOT_POSITIVE
            if not (isinstance(b, list) and not b)
        ],
        ("frequency_sigma", {"frequencies": [10.0, 20.0]}),
        ("frequency_sigma", {"frequencies": [10.0, 20.0], "frequency_sigma": [1.0] * 3}),
        *[("damping_ratios", {"damping_ratios": b, "damping_sigma": 0.1}) for b in NOT_POSITIVE],
        ("damping_ratios", {"damping_ratios": [2.0], "damping_sigma": 0.1}),  # zeta >= 1
        (
            "frequency_modes",
            {"frequencies": [1.0] * 3, "frequency_sigma": 1, "frequency_modes": [0.5, 1, 2]},
        ),
        (
            "frequency_modes",
            {"frequencies": [1.0] * 3, "frequency_sigma": 1, "frequency_modes": [-1, 0, 1]},
        ),
        (
            "frequency_modes",
            {"frequencies": [1.0] * 3, "frequency_sigma": 1, "frequency_modes": []},
        ),
        (
            "frequency_modes",
            {"frequencies": [1.0] * 3, "frequency_sigma": 1, "frequency_modes": "abc"},
        ),
        *[
            ("shapes", {"shapes": b, "shape_sigma": 0.1})
            for b in (NAN, INF, [], "abc", Q_(1.0, "m"))
        ],
        ("shapes", {"shapes": np.ones((2, 2, 2)), "shape_sigma": 0.1}),
        *[
            ("shape_sigma", {"shapes": np.eye(3), "shape_sigma": b})
            for b in (NAN, INF, -1.0, 0.0, "abc")
        ],
        ("shape_sigma", {"shapes": np.eye(3), "shape_sigma": np.ones((2, 2))}),
        ("shape_dofs", {"shapes": np.eye(3), "shape_sigma": 0.1, "shape_dofs": [0, 0, 1]}),
        ("shape_dofs", {"shapes": np.eye(3), "shape_sigma": 0.1, "shape_dofs": [NAN] * 3}),
        *[
            (
                "orthogonality_sigma",
                {"shapes": np.eye(3), "shape_sigma": 0.1, "orthogonality_sigma": b},
            )
            for b in (NAN, INF, -1.0, 0.0, "abc", [1.0, 2.0])
        ],
        ("frequencies", {}),  # no measurement at all
        ("frf", {"frf": 5}),
        ("frf", {"frf": None}),
        ("frf[0]", {"frf": [5]}),
        *[
            ("frf[0].omegas", {"frf": [(0, 0, b, [1.0], 0.01)]})
            for b in (NAN, INF, "abc", -1.0, 0.0)
        ],
        ("frf[0]", {"frf": [(0, 0, [], [], 0.01)]}),
        *[("frf[0].values", {"frf": [(0, 0, [1.0], b, 0.01)]}) for b in (NAN, INF, "abc")],
        *[
            ("frf[0].sigma", {"frf": [(0, 0, [1.0], [1.0], b)]})
            for b in (NAN, INF, "abc", -1.0, 0.0, Q_(1.0, "m"), [1.0, 2.0])
        ],
        ("frf[0].output_gain", {"frf": [(0, 0, [1.0], [1.0], 0.01, -1, None)]}),
        ("frf[0].output_gain", {"frf": [(0, 0, [1.0], [1.0], 0.01, 1.5, None)]}),
        ("frf[0].output_gain", {"frf": [(0, 0, [1.0], [1.0], 0.01, 10**12, None)]}),  # 10**12 gains
        ("frf[0].input_gain", {"frf": [(0, 0, [1.0], [1.0], 0.01, None, True)]}),
    ],
    ids=stable_id,
)
def test_correction_data_refuses_by_name(field, kwargs):
    _raises(field, lambda: CorrectionData(**kwargs))


@pytest.mark.parametrize(
    "field, output",
    [
        ("frf[0].output", "a"),
        ("frf[0].output", 9),
        ("frf[0].output", -1),
        ("frf[0].output", 1.5),
        ("frf[0].output", True),
        ("frf[0].output", np.full(3, NAN)),
        ("frf[0].output", np.ones(4)),
    ],
    ids=stable_id,
)
def test_frf_outputs_refused_against_the_model_before_the_fit(chain, field, output):
    """Checked against the model first: the count of measurements does not hide them."""
    data = CorrectionData(frf=[(output, 0, OMEGAS, _frf(chain), 0.01)])
    _raises(field, lambda: differential_correction(chain, data))


@pytest.mark.parametrize(
    "field, data",
    [
        (
            "frequency_modes",
            CorrectionData(frequencies=[1.0] * 3, frequency_sigma=0.1, frequency_modes=[0, 1, 9]),
        ),
        ("shapes", CorrectionData(shapes=np.ones((4, 2)), shape_sigma=0.1)),
        ("shape_dofs", CorrectionData(shapes=np.ones((2, 2)), shape_sigma=0.1, shape_dofs=[0, 5])),
    ],
    ids=["mode 9 of 3", "4 rows for 3 dofs", "dof 5 of 3"],
)
def test_data_beyond_the_model_refused_by_name(chain, field, data):
    _raises(field, lambda: differential_correction(chain, data))


def test_damping_ratios_need_damping_blocks(chain):
    model = SubstructureModel(chain.K_blocks, chain.M_blocks)
    data = CorrectionData(damping_ratios=[0.01, 0.02, 0.03], damping_sigma=0.1)
    _raises("damping_ratios", lambda: differential_correction(model, data))


@pytest.mark.parametrize(
    "field, changes",
    [
        ("model", {"model": None}),
        ("data", {"data": None}),
        *[("p0", {"p0": [b] * 3}) for b in (NAN, INF, "abc", -1.0, 0.0, 1 + 1j)],
        ("p0", {"p0": []}),
        ("p0", {"p0": Q_([1.0] * 3, "m")}),
        ("q0", {"q0": [-1.0, 1.0, 1.0]}),  # M(q0) indefinite
        ("r0", {"r0": [NAN] * 3}),
        *[
            ("prior_sigma", {"prior_sigma": b})
            for b in (NAN, INF, [], "abc", Q_(1.0, "m"), -1.0, 0.0)
        ],
        *[("n_iter", {"n_iter": b}) for b in (NAN, INF, [], "abc", Q_(1.0, "m"), -1, 0, 1.5, True)],
        ("n_iter", {"n_iter": limits.MAX_FIT_ITERATIONS + 1}),  # was: runs for ever with tol=0
        *[("tol", {"tol": b}) for b in (NAN, INF, [], "abc", Q_(1.0, "m"), -1.0, 1 + 1j)],
        *[("fixed_stiffness", {"fixed_stiffness": b}) for b in ([0.5], [7], [-1], "a")],
        (
            "fixed_stiffness",
            {"fixed_stiffness": [0, 1, 2], "fixed_mass": [0, 1, 2], "fixed_damping": [0, 1, 2]},
        ),
        ("mu0", {"mu0": [1.0]}),  # the data name no output gain
    ],
    ids=stable_id,
)
def test_differential_correction_refuses_by_name(chain, data, field, changes):
    given = {"model": chain, "data": data, **changes}
    _raises(field, lambda: differential_correction(**given))


def test_predict_refuses_by_name(chain, data):
    gains = CorrectionData(frf=[(0, 0, OMEGAS, _frf(chain), 0.01, 0, None)])
    _raises("mu", lambda: gains.predict(chain, mu=[NAN]))
    _raises("p", lambda: data.predict(chain, p="abc"))
    _raises("model", lambda: data.predict(None))


def test_valid_data_still_correct_the_chain(chain, data):
    """The checks refuse only what they should: exact data of the nominal chain are fitted
    at the nominal scalings from 5 % off (Gauss-Newton to round-off)."""
    res = differential_correction(chain, data, p0=[1.05] * 3, q0=[0.95] * 3)
    assert res.converged
    assert np.allclose(np.r_[res.p, res.q, res.r], 1.0, atol=1e-6)
