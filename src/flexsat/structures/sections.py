"""Isotropic materials and beam cross-sections (all SI).

Section properties follow the frame convention of :mod:`flexsat.structures.elements`: local x is
the member axis, ``Iz`` governs bending in the local x-y plane, ``Iy`` bending in the local x-z
plane and ``J`` is the Saint-Venant torsion constant.  Formulas: Young, Budynas & Sadegh,
*Roark's Formulas for Stress and Strain*, 8th ed., Table 10.1 (torsion) and Appendix A
(areas and second moments); Timoshenko & Goodier, *Theory of Elasticity*, §109 (rectangle).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from flexsat.input_checks import FieldError, require_finite, require_nonneg, require_positive

__all__ = ["Material", "Section"]

_RECT_TERMS = 40  # odd terms n = 1, 3, ..., 79 of the rectangle torsion series (rel. error < 1e-10)


def _positive(value: float, field: str) -> float:
    return float(require_positive(value, field))


@dataclass(frozen=True)
class Material:
    """Linear-elastic isotropic material.

    Attributes
    ----------
    E : float
        Young's modulus, Pa (> 0).
    rho : float
        Density, kg/m^3 (>= 0; 0 gives massless members, e.g. springs between lumped masses).
    nu : float
        Poisson's ratio, -1 < nu < 0.5 (used only when ``G`` is not given).
    G : float or None
        Shear modulus, Pa (> 0); defaults to E / (2 (1 + nu)).
    name : str
        Free label.
    """

    E: float
    rho: float
    nu: float = 0.3
    G: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "E", _positive(self.E, "E"))
        object.__setattr__(self, "rho", float(require_nonneg(self.rho, "rho")))
        nu = float(require_finite(self.nu, "nu"))
        if not -1.0 < nu < 0.5:
            raise FieldError("nu", f"must satisfy -1 < nu < 0.5, got {self.nu!r}")
        object.__setattr__(self, "nu", nu)
        if self.G is not None:
            object.__setattr__(self, "G", _positive(self.G, "G"))

    @property
    def shear_modulus(self) -> float:
        """G if given, else E / (2 (1 + nu)), Pa."""
        return self.G if self.G is not None else self.E / (2.0 * (1.0 + self.nu))


@dataclass(frozen=True)
class Section:
    """Beam cross-section properties.

    Attributes
    ----------
    A : float
        Area, m^2.
    Iy, Iz : float
        Second moments of area about local y (bending in the x-z plane) and local z (bending in
        the x-y plane), m^4.
    J : float
        Saint-Venant torsion constant, m^4.
    name : str
        Free label.
    """

    A: float
    Iy: float
    Iz: float
    J: float
    name: str = ""

    def __post_init__(self) -> None:
        for field in ("A", "Iy", "Iz", "J"):
            object.__setattr__(self, field, _positive(getattr(self, field), field))

    @classmethod
    def general(cls, A: float, Iy: float, Iz: float, J: float, name: str = "") -> Section:
        """Section from given properties (same as the constructor)."""
        return cls(A, Iy, Iz, J, name)

    @classmethod
    def tube(cls, outer_diameter: float, thickness: float, name: str = "") -> Section:
        r"""Circular tube, exact for any wall thickness.

        With :math:`D` the outer and :math:`d = D - 2t` the inner diameter:
        :math:`A = \pi (D^2 - d^2)/4`, :math:`I_y = I_z = \pi (D^4 - d^4)/64`,
        :math:`J = 2 I_y` (polar moment; exact for circular sections).

        Parameters
        ----------
        outer_diameter : float
            D, m (> 0).
        thickness : float
            Wall thickness t, m, 0 < t <= D/2 (t = D/2 is a solid circle).
        """
        D = _positive(outer_diameter, "outer_diameter")
        t = _positive(thickness, "thickness")
        if t > D / 2:
            raise FieldError(
                "thickness", f"must be <= outer_diameter / 2 = {D / 2!r}, got {thickness!r}"
            )
        d = max(D - 2.0 * t, 0.0)
        A = math.pi * (D * D - d * d) / 4.0
        inertia = math.pi * (D**4 - d**4) / 64.0
        return cls(A, inertia, inertia, 2.0 * inertia, name)

    @classmethod
    def circle(cls, diameter: float, name: str = "") -> Section:
        """Solid circle of the given diameter, m."""
        D = _positive(diameter, "diameter")
        return cls.tube(D, D / 2.0, name)

    @classmethod
    def rectangle(cls, width: float, height: float, name: str = "") -> Section:
        r"""Solid rectangle, ``width`` along local y and ``height`` along local z.

        :math:`A = b h`, :math:`I_z = h b^3 / 12`, :math:`I_y = b h^3 / 12`, and with
        :math:`a \ge c` the long and short sides the Saint-Venant series (Timoshenko & Goodier
        §109)

        .. math::

            J = \frac{a c^3}{3} \left[ 1 - \frac{192}{\pi^5} \frac{c}{a}
                \sum_{n = 1, 3, 5, \dots} \frac{\tanh(n \pi a / 2c)}{n^5} \right],

        summed over 40 odd terms (truncation error below 1e-10 relative).
        """
        b = _positive(width, "width")
        h = _positive(height, "height")
        a, c = max(b, h), min(b, h)
        n = np.arange(1, 2 * _RECT_TERMS, 2, dtype=float)
        series = np.sum(np.tanh(n * math.pi * a / (2.0 * c)) / n**5)
        J = a * c**3 / 3.0 * (1.0 - 192.0 / math.pi**5 * (c / a) * series)
        return cls(b * h, b * h**3 / 12.0, h * b**3 / 12.0, float(J), name)
