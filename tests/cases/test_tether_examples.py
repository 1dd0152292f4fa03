"""The Vadali & Kim examples (flexsat.cases.tether): the laws they name, the measures of a
rerun in the paper's units, and an unknown law refused by name."""

import numpy as np
import pytest

from flexsat.cases.tether import EXAMPLES, INITIAL, make_law, measures, paper_scales, rerun
from flexsat.control.tether_laws import CoupledTetherLaw, DecoupledTetherLaw, TetherRateLaw


def test_examples_name_their_laws_and_the_paper_start():
    assert INITIAL == (1.0, np.radians(5), np.radians(5), 0.0, 0.0, 0.0)
    kinds = {"decoupled": DecoupledTetherLaw, "coupled": CoupledTetherLaw, "rate": TetherRateLaw}
    for e in EXAMPLES.values():
        law = make_law(e.law, e.gains, e.final_length)
        assert isinstance(law, kinds[e.law]), e.key
        assert law.final_length == e.final_length


def test_measures_of_the_v11_rerun_in_paper_units():
    m = measures(rerun("V11"), 0.01, paper_scales(), "coupled")
    assert m["thrust_index_2_orbits"] == pytest.approx(0.2369, abs=5e-4)
    assert m["thrust_impulse_2_orbits_Ns"] == pytest.approx(0.2369 * 534.8, abs=0.3)
    assert m["initial_tension_N"] == pytest.approx(3.99 * 0.630, abs=0.005)
    assert m["initial_rate_m_s"] is None
    assert m["final_length_m"] == pytest.approx(0.0093 * 2e4, abs=2)


def test_unknown_law_is_refused():
    with pytest.raises(ValueError, match="law: must be 'decoupled', 'coupled' or 'rate'"):
        make_law("bang-bang", {}, 0.01)
