"""Materials and cross-sections against closed forms and published tables.

Tolerances: closed forms are evaluated in double precision (rtol 1e-14); the rectangle torsion
constant is compared with the 4-digit values of Timoshenko & Goodier, *Theory of Elasticity*,
§109 table (k1 = 0.1406, 0.2287, 0.3123 for a/b = 1, 2, 10), so rtol 5e-4 (half a unit in the
last published digit relative to the value).
"""

from __future__ import annotations

import math

import pytest

from flexsat.structures import Material, Section


def test_material_shear_modulus_default_and_given():
    assert Material(E=200e9, rho=7800.0, nu=0.25).shear_modulus == pytest.approx(80e9, rel=1e-14)
    assert Material(E=200e9, rho=7800.0, G=70e9).shear_modulus == 70e9
    assert Material(E=1.0, rho=0.0).rho == 0.0  # massless members are allowed


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(E=0.0, rho=1.0), "E: must be > 0"),
        (dict(E=float("nan"), rho=1.0), "E: must be finite"),
        (dict(E=1.0, rho=-1.0), "rho: must be >= 0"),
        (dict(E=1.0, rho=1.0, nu=0.5), "nu: must satisfy -1 < nu < 0.5"),
        (dict(E=1.0, rho=1.0, G=-2.0), "G: must be > 0"),
        (dict(E="70 GPa", rho=1.0), "E: must be a number in SI units"),
    ],
)
def test_material_errors(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Material(**kwargs)


def test_circle_and_thick_tube_closed_forms():
    D, t = 0.1, 0.01
    d = D - 2 * t
    s = Section.tube(D, t)
    assert s.A == pytest.approx(math.pi * (D**2 - d**2) / 4, rel=1e-14)
    assert s.Iy == s.Iz == pytest.approx(math.pi * (D**4 - d**4) / 64, rel=1e-14)
    assert s.J == pytest.approx(math.pi * (D**4 - d**4) / 32, rel=1e-14)
    c = Section.circle(D)
    assert (c.A, c.Iy, c.J) == pytest.approx(
        (math.pi * D**2 / 4, math.pi * D**4 / 64, math.pi * D**4 / 32), rel=1e-14
    )


def test_thin_tube_limit():
    """Thin wall: A = pi D_m t, I = pi D_m^3 t / 8 with D_m the mean diameter (error O((t/D)^2))."""
    D, t = 1.0, 1e-4
    s, Dm = Section.tube(D, t), D - t
    assert s.A == pytest.approx(math.pi * Dm * t, rel=1e-7)
    assert s.Iy == pytest.approx(math.pi * Dm**3 * t / 8, rel=1e-7)


@pytest.mark.parametrize("ratio, k1", [(1.0, 0.1406), (2.0, 0.2287), (10.0, 0.3123)])
def test_rectangle_torsion_constant_table(ratio, k1):
    s = Section.rectangle(ratio * 0.02, 0.02)
    assert s.J == pytest.approx(k1 * ratio * 0.02 * 0.02**3, rel=5e-4)


def test_rectangle_axes_and_thin_strip_limit():
    s = Section.rectangle(width=0.3, height=0.1)  # width along local y
    assert s.Iz == pytest.approx(0.1 * 0.3**3 / 12, rel=1e-14)
    assert s.Iy == pytest.approx(0.3 * 0.1**3 / 12, rel=1e-14)
    assert s.J == pytest.approx(Section.rectangle(0.1, 0.3).J, rel=1e-14)
    # a/b -> infinity (tanh -> 1): J = a b^3 (1/3 - c b/a), c = 64/pi^5 sum_(n odd) n^-5 = 0.21010
    strip = Section.rectangle(100.0, 1.0)
    assert strip.J == pytest.approx(100.0 * (1 / 3 - 0.21010 / 100), rel=1e-6)


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: Section(1.0, 1.0, 0.0, 1.0), "Iz: must be > 0"),
        (lambda: Section.general(-1.0, 1.0, 1.0, 1.0), "A: must be > 0"),
        (lambda: Section.tube(0.1, 0.06), "thickness: must be <= outer_diameter / 2"),
        (lambda: Section.tube(0.1, 0.0), "thickness: must be > 0"),
        (lambda: Section.rectangle(float("inf"), 1.0), "width: must be finite"),
    ],
)
def test_section_errors(call, message):
    with pytest.raises(ValueError, match=message):
        call()
