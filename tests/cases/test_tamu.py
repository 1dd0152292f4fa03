"""The TAMU hub + appendage experiment (Junkins, Pollock & Rahman 1990, Att. 1-3)."""

import numpy as np
import pytest

from flexsat.cases import CASES, get_case, tamu
from flexsat.cases.tamu import inertia_budget

OZ_IN_S2 = 0.278013851 * 0.0254  # kg m² per ozf in s², by hand, to check the pint path
OZ_IN = 0.278013851 * 0.0254  # N m per ozf in


def test_published_units_are_converted_with_pint(tamu_case):
    assert tamu_case.reference_inertia == pytest.approx(2128 * OZ_IN_S2, rel=1e-9)
    assert tamu_case.max_torque == pytest.approx(400 * OZ_IN, rel=1e-9)
    assert tamu_case.angle == pytest.approx(np.radians(40), rel=1e-15)


def test_inertia_budget_shows_the_table_1_inconsistency(tamu_case):
    """Notes §2.1 [DERIVED]: 4 [ρ(l³ − l0³)/3 + m l²] = 2163.6 oz-in-s² with ρ = 0.003007,
    which exceeds the published total of 2128."""
    b = inertia_budget(tamu_case)
    appendages = (b["beams"] + b["tip_masses"]) / OZ_IN_S2
    assert appendages == pytest.approx(4 * 540.91, rel=1e-4)
    assert appendages > 2128
    assert b["total_model"] == pytest.approx(b["hub"] + b["beams"] + b["tip_masses"], rel=1e-14)


@pytest.mark.parametrize("alpha,T", [(0.0, 3.8544), (0.1, 4.2986), (0.2, 4.9109)])
def test_maneuver_time_of_the_40_degree_slew(tamu_case, alpha, T):
    """Issue acceptance / notes §2.4 table: I = 2128 oz-in-s², 40°, u_max = 400 oz-in, to 1e-4 s;
    the reference ends exactly at rest on target."""
    ref = tamu_case.reference(alpha=alpha)
    assert float(ref.end_time) == pytest.approx(T, abs=1e-4)
    r = ref(float(ref.end_time))
    assert abs(float(r.theta) - tamu_case.angle) < 1e-12
    assert abs(float(r.theta_dot)) < 1e-12


def test_overrides_accept_units_and_reject_unknown_names():
    c = tamu(hub_inertia="30 ozf*in*s**2", n_modes=4)
    assert c.hub_inertia == pytest.approx(30 * OZ_IN_S2, rel=1e-9)
    assert c.model().n_modes == 4
    with pytest.raises(ValueError, match=r"^tamu: unknown parameter\(s\) \['hub_inertai'\]"):
        tamu(hub_inertai=1.0)
    with pytest.raises(ValueError, match=r"^hub_inertia: must be > 0"):
        tamu(hub_inertia=0.0)
    with pytest.raises(ValueError, match=r"^density: incompatible units"):
        tamu(density="3 kg")
    with pytest.raises(ValueError, match=r"^tip_radius: must exceed hub_radius"):
        tamu(tip_radius="5 in")
    with pytest.raises(ValueError, match=r"^modulus: must be > 0"):
        tamu(modulus="-1 psi")
    with pytest.raises(ValueError, match=r"^n_modes: must be finite"):
        tamu(n_modes=float("nan"))
    with pytest.raises(ValueError, match=r"^n_modes: must be a positive integer"):
        tamu(n_modes=2.5)
    with pytest.raises(ValueError, match=r"^stiffening: must be true or false"):
        tamu(stiffening="yes")
    assert tamu(stiffening="false").stiffening is False


def test_case_registry():
    assert "tamu" in CASES and "Table 1" in CASES["tamu"].source
    with pytest.raises(ValueError, match=r"^case: unknown case 'hst'"):
        get_case("hst")


@pytest.mark.parametrize(
    "override",
    [
        {"tip_mass": "1.5627 ozf*s**2/in"},  # 10× the tip masses: ~8× the inertia
        {"hub_inertia": "500 ozf*in*s**2"},
        {"tip_radius": "40 in", "density": "0.00307 ozf*s**2/in**2"},
        {"n_appendages": 2, "tip_inertia": "10 ozf*in*s**2"},
    ],
)
def test_inertia_overrides_move_the_reference_design_inertia(override):
    """The reference is designed on the published total scaled with the vehicle: the same
    design-to-model ratio 2128 / 2213.6 as the default case (to rounding of one division,
    1e-14), so the slew time at the same torque and α grows as √I (Eq. 16: T² ∝ I)."""
    nominal, case = tamu(), tamu(**override)
    ratio = nominal.reference_inertia / nominal.params.total_inertia
    assert ratio == pytest.approx(2128 / 2213.6, rel=5e-5)  # budget printed to 5 digits
    grown = case.params.total_inertia / nominal.params.total_inertia
    assert abs(grown - 1) > 0.05  # the override does change the vehicle
    assert case.reference_inertia / case.params.total_inertia == pytest.approx(ratio, rel=1e-14)
    T, T0 = float(case.reference().end_time), float(nominal.reference().end_time)
    assert T / T0 == pytest.approx(np.sqrt(grown), rel=1e-14)
    assert inertia_budget(case)["reference_design"] == case.reference_inertia
    assert inertia_budget(case)["published_total"] == pytest.approx(2128 * OZ_IN_S2, rel=1e-9)


def test_reference_inertia_given_or_untouched_by_non_inertia_overrides():
    # an explicit reference_inertia is the design inertia, whatever the vehicle
    c = tamu(tip_mass="1.5627 ozf*s**2/in", reference_inertia="2128 ozf*in*s**2")
    assert c.reference_inertia == pytest.approx(2128 * OZ_IN_S2, rel=1e-9)
    # stiffness, damping and the model size leave the rigid inertia and so the published value
    c = tamu(modulus="100e6 ozf/in**2", damping=0.02, n_modes=4, stiffening=True)
    assert c.reference_inertia == tamu().reference_inertia
    with pytest.raises(ValueError, match=r"^reference_inertia: must be > 0"):
        tamu(reference_inertia=-1.0)
