"""Bad input to the test excitations (:mod:`flexsat.identify.excitation`) is refused by name
when the excitation is built, not later in the test: every call below raises a
:class:`~flexsat.input_checks.FieldError` whose field is the parameter at fault."""

from __future__ import annotations

import numpy as np
import pytest

from flexsat.identify import Channel
from flexsat.identify.excitation import (
    Excitation,
    harmonic_shaker,
    impulse_hammer,
    random_force,
    torque_history,
)
from flexsat.input_checks import FieldError
from flexsat.units import Q_

NAN, INF = np.nan, np.inf
NOT_A_NUMBER = [NAN, INF, [], "abc", Q_(1.0, "m"), 1 + 1j, np.ones(2)]
FORCE = Channel.at("force", 1, "z")


def _raises(field, call):
    with pytest.raises(FieldError) as err:
        call()
    assert err.value.field.startswith(field), str(err.value)
    assert str(err.value).startswith(field)


@pytest.mark.parametrize(
    "field, call",
    [
        *[("amplitude", lambda b=b: impulse_hammer(1, "z", b)) for b in NOT_A_NUMBER],
        *[("width", lambda b=b: impulse_hammer(1, "z", 1.0, b)) for b in NOT_A_NUMBER[:6]],
        ("width", lambda: impulse_hammer(1, "z", 1.0, -1e-3)),
        ("width", lambda: impulse_hammer(1, "z", 1.0, Q_(1.0, "m"))),
        ("load", lambda: impulse_hammer(1, "z", load="pressure")),
        *[("frequency", lambda b=b: harmonic_shaker(1, "z", 1.0, b)) for b in NOT_A_NUMBER],
        ("frequency", lambda: harmonic_shaker(1, "z", 1.0, 0.0)),
        ("amplitude", lambda: harmonic_shaker(1, "z", NAN, 1.0)),
        *[("rms", lambda b=b: random_force(1, "z", b)) for b in NOT_A_NUMBER],
        ("rms", lambda: random_force(1, "z", -1.0)),
        *[
            ("values", lambda b=b: torque_history(1, "z", b))
            for b in (NAN, [], "abc", [1.0, NAN], np.ones((2, 2)), Q_([1.0], "N*m"))
        ],
        ("kind", lambda: Excitation("step", FORCE)),
        ("channel", lambda: Excitation("random", "force at 1 z")),
        ("channel", lambda: Excitation("random", Channel.at("displacement", 1, "z"))),
        ("frequency", lambda: Excitation("harmonic", FORCE)),
        ("values", lambda: Excitation("history", FORCE)),
    ],
)
def test_excitations_refuse_by_name(field, call):
    _raises(field, call)


def test_a_width_in_ms_is_read_in_seconds():
    assert impulse_hammer(1, "z", 2.0, Q_(5.0, "ms")).width == pytest.approx(5e-3, rel=1e-15)
    assert impulse_hammer(1, "z", 2.0, "5 ms").width == pytest.approx(5e-3, rel=1e-15)
