r"""Beam benchmarks of the finite-element core: uniform cantilever, free-free beam, NAFEMS FV2.

Uniform beams
-------------
A straight uniform beam along global X, ``n_elements`` 3-D Euler-Bernoulli frame elements
(:meth:`flexsat.structures.fem.Structure.add_frame`), solid rectangular section ``width`` along
global Y and ``height`` along global Z.  Default: aluminium alloy flat bar 1 m x 40 mm x 10 mm
(E = 70 GPa, rho = 2700 kg/m³, nu = 0.33), so the two bending planes are distinct:

* **flatwise** bending, in the X-Z plane (uz, ry), second moment ``Iy = w h³/12``, the weak plane;
* **edgewise** bending, in the X-Y plane (uy, rz), ``Iz = h w³/12`` (16 times stiffer by default).

Each mode is classified by where its kinetic energy sits (mass-matrix partition over the dof
families axial ux, edgewise uy/rz, flatwise uz/ry, torsion rx) and the Euler-Bernoulli
eigenvalue of every bending mode is recovered from its frequency,

.. math::

    \beta L = \left( \omega^2 \frac{\rho A L^4}{E I} \right)^{1/4},

to be compared with the exact roots of :math:`1 + \cos z \cosh z = 0` (clamped-free) and
:math:`1 - \cos z \cosh z = 0` (free-free) tabulated by Blevins, *Formulas for Natural
Frequency and Mode Shape* (1979), Table 8-1: 1.875104, 4.694091, 7.854757, 10.995541 and
4.730041, 7.853205, 10.995608.  The free-free 3-D frame has exactly six rigid-body modes; they
are solved for (``rigid_body_modes=6``) and dropped.

NAFEMS FV2
----------
NAFEMS, *Selected Benchmarks for Natural Frequency Analysis* (R0015, 1987; also *The Standard
NAFEMS Benchmarks*, TNSB Rev. 3, 1990), test FV2 "pin-ended double cross, in-plane vibration":
**four** members 10 m long crossing at their common centre at 45° to each other, i.e. eight arms
of 5 m at 0°, 45°, ..., 315°, solid square section 0.125 m, E = 200 GPa, rho = 8000 kg/m³, each
arm four elements, the x and y translations fixed at the eight arm tips, motion in the plane of
the cross only.  Reference frequencies: 11.336 Hz (mode 1), 17.709 Hz (modes 2-8), 45.345 Hz
(mode 9), 57.390 Hz (modes 10-16).  Closed form: the centre cannot translate (the arms are
axially stiff), so the modes are arm bending with the centre rotating (pinned-pinned arms,
βL = π, 2π: modes 1 and 9) or fixed (clamped-pinned arms, βL = 3.9266, 7.0686, seven
combinations each with zero net moment at the centre).

The default model uses the planar beam element (``add_beam2d``: ux, uy, rz).  With
``plane="3d"`` the cross is built from 3-D frames with x, y and z fixed at the tips (one reading
of "pin-ended"); it adds out-of-plane modes (2.83 Hz: the centre bouncing, arms pinned-sliding;
11.33 Hz twice: the centre rocking; ...), so the published list is the in-plane spectrum only
(see docs/structures_benchmarks.md).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.input_checks import FieldError, require_count
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material, Section
from flexsat.units import to_si

if TYPE_CHECKING:
    from flexsat.dynamics.structural import StructuralPlant

__all__ = [
    "CANTILEVER_BETA_L",
    "FREE_FREE_BETA_L",
    "FV2_REFERENCE_HZ",
    "PUBLISHED",
    "BeamCase",
    "Fv2Case",
    "cantilever_beam",
    "free_free_beam",
    "nafems_fv2",
]

#: Exact βL (Blevins 1979, Table 8-1), as printed to 6 decimals
PUBLISHED: dict[str, Any] = {
    "cantilever_beta_L": (1.875104, 4.694091, 7.854757, 10.995541),
    "free_free_beta_L": (4.730041, 7.853205, 10.995608),
    "fv2_frequencies": ("11.336 Hz", "17.709 Hz", "45.345 Hz", "57.390 Hz"),
    "fv2_multiplicities": (1, 7, 1, 7),
    "fv2_arm_length": "5 m",
    "fv2_side": "0.125 m",
    "fv2_modulus": "200 GPa",
    "fv2_density": "8000 kg/m**3",
}
SOURCE_BEAMS = CASES["cantilever_beam"].source
SOURCE_FV2 = CASES["nafems_fv2"].source

CANTILEVER_BETA_L = np.array(PUBLISHED["cantilever_beta_L"])
FREE_FREE_BETA_L = np.array(PUBLISHED["free_free_beta_L"])
FV2_REFERENCE_HZ = np.repeat(
    [to_si(f, "Hz") for f in PUBLISHED["fv2_frequencies"]], PUBLISHED["fv2_multiplicities"]
)

# dof families of a beam along X with width along Y and height along Z
_FAMILIES = {
    "axial": ("ux",),
    "edgewise": ("uy", "rz"),  # X-Y plane, Iz
    "flatwise": ("uz", "ry"),  # X-Z plane, Iy
    "torsion": ("rx",),
}
_PLANES = {"flatwise": "flatwise", "xz": "flatwise", "edgewise": "edgewise", "xy": "edgewise"}


def _poisson(raw, name: str) -> float:
    """Poisson's ratio (dimensionless), -1 < nu < 0.5."""
    nu = to_si(raw, "", name)
    if not -1.0 < nu < 0.5:
        raise FieldError(name, f"must satisfy -1 < nu < 0.5, got {raw!r}")
    return nu


# ------------------------------------------------------------------------------------------------
# uniform beams
_BEAM_INPUTS = {
    "length": Param("1 m", "m"),
    "E": Param("70 GPa", "Pa"),
    "rho": Param("2700 kg/m**3", "kg/m**3"),
    "nu": Param(0.33, rule=_poisson),
    "width": Param("40 mm", "m"),
    "height": Param("10 mm", "m"),
    "n_elements": Param(20, rule="count", limit="MAX_ELEMENTS"),
    "lumped": Param(False, rule="flag"),
}


@dataclass(frozen=True)
class BeamCase:
    """A uniform 3-D frame beam, clamped at x = 0 (``boundary="cantilever"``) or free-free."""

    boundary: str
    length: float
    E: float
    rho: float
    nu: float
    width: float
    height: float
    n_elements: int
    lumped: bool
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def material(self) -> Material:
        return Material(E=self.E, rho=self.rho, nu=self.nu, name="beam")

    @property
    def section(self) -> Section:
        return Section.rectangle(self.width, self.height, name="beam")

    @property
    def exact_beta_L(self) -> np.ndarray:
        return CANTILEVER_BETA_L if self.boundary == "cantilever" else FREE_FREE_BETA_L

    @property
    def rigid_body_modes(self) -> int:
        return 0 if self.boundary == "cantilever" else 6

    def structure(self) -> Structure:
        """Nodes 0..n along X, ``n_elements`` frames (width along global Y: ``orientation`` Y)."""
        s = Structure(f"{self.boundary} beam")
        x = np.linspace(0.0, self.length, self.n_elements + 1)
        for i, xi in enumerate(x):
            s.add_node(i, (xi, 0.0, 0.0))
        for i in range(self.n_elements):
            s.add_frame(
                i,
                i + 1,
                self.material,
                self.section,
                orientation=(0.0, 1.0, 0.0),
                lumped=self.lumped,
                label=f"beam {i + 1}",
            )
        if self.boundary == "cantilever":
            s.clamp(0)
        return s

    def plant(self, n_modes: int = 8, damping: float = 0.01) -> StructuralPlant:
        """The beam as a plant: a transverse (z) force ``force`` at the tip, the tip and
        mid-span displacements ``displacement_<node>`` (m) and their rates, on the modal model
        of its first ``n_modes`` modes (the six rigid modes of a free beam included) with
        ``damping`` on each elastic mode (:mod:`flexsat.cases.structure_plants`)."""
        from flexsat.cases.structure_plants import first_modes, point_force_plant

        n = self.n_elements
        modes = first_modes(self.structure(), n_modes, self.rigid_body_modes or None)
        return point_force_plant(modes, n, [n, n // 2], "z", damping)

    @property
    def square(self) -> bool:
        """Equal bending stiffness in both planes (then each bending frequency is double)."""
        sec = self.section
        return abs(sec.Iy - sec.Iz) <= 1e-9 * max(sec.Iy, sec.Iz)

    def _solve(self, n_elastic: int):
        """At least ``n_elastic`` elastic modes (more when cached): frequencies (Hz) and the
        family of each mode (largest share of the kinetic energy φ_i (Mφ)_i)."""
        cached = self._cache.get("modes")
        if cached is None or len(cached[0]) < n_elastic:
            asm = self.structure().assemble()
            r = self.rigid_body_modes
            k = min(asm.n_dofs, r + max(n_elastic, 2 * (cached[0].size if cached else 20)))
            modes = asm.modes(k, rigid_body_modes=r or None)
            shapes = modes.shapes[:, r:]
            energy = shapes * (asm.M @ shapes)
            names = np.array([d for _, d in asm.dofs])
            shares = np.stack(
                [energy[np.isin(names, dofs)].sum(axis=0) for dofs in _FAMILIES.values()], axis=1
            )
            family = np.array(list(_FAMILIES))[np.argmax(shares, axis=1)]
            if self.square:  # degenerate pairs: any mix of the two planes is a mode
                bending = np.isin(family, ("flatwise", "edgewise"))
                family[bending] = np.where(
                    np.arange(bending.sum()) % 2 == 0, "flatwise", "edgewise"
                )
            cached = self._cache["modes"] = (
                modes.omegas[r:] / (2 * np.pi),
                family,
                k == asm.n_dofs,
            )
        return cached

    def _family(self, name: str, n: int) -> np.ndarray:
        """First ``n`` frequencies of a family, solving for more modes as needed."""
        m = n
        while True:
            f, family, complete = self._solve(m)
            own = f[family == name]
            if len(own) >= n or complete:
                break
            m = 2 * len(f)
        if len(own) < n:
            raise FieldError(
                "n_modes",
                f"the model has {len(own)} {name} bending modes "
                f"with n_elements = {self.n_elements}, got {n}",
            )
        return own[:n].copy()

    # -- case protocol --------------------------------------------------------------------------
    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        """First ``n_modes`` elastic frequencies of the 3-D model (all families), Hz."""
        n = require_count(n_modes, "n_modes")
        f, _, _ = self._solve(n)
        if n > len(f):
            raise FieldError("n_modes", f"the model has {len(f)} elastic modes, got {n}")
        return f[:n].copy()

    def mode_descriptions(self, n_modes: int) -> list[str]:
        """``"flatwise bending 1"``, ``"edgewise bending 1"``, ``"torsion 1"``, ``"axial 1"``…"""
        n = require_count(n_modes, "n_modes")
        _, family, _ = self._solve(n)
        counts: dict[str, int] = {}
        out = []
        for fam in family[:n]:
            counts[fam] = counts.get(fam, 0) + 1
            kind = fam if fam in ("torsion", "axial") else f"{fam} bending"
            out.append(f"{kind} {counts[fam]}")
        return out

    def bending_frequencies_hz(self, n_modes: int, plane: str = "flatwise") -> np.ndarray:
        """First ``n_modes`` bending frequencies (Hz) in ``plane``: "flatwise" (alias "xz") or
        "edgewise" (alias "xy")."""
        n = require_count(n_modes, "n_modes")
        if plane not in _PLANES:
            raise FieldError("plane", f"must be one of {sorted(_PLANES)}, got {plane!r}")
        return self._family(_PLANES[plane], n)

    def beta_L(self, n_modes: int, plane: str = "flatwise") -> np.ndarray:
        """βL = (ω² ρA L⁴ / EI)^(1/4) of the first ``n_modes`` FE bending modes in ``plane``."""
        omega = 2 * np.pi * self.bending_frequencies_hz(n_modes, plane)
        sec = self.section
        EI = self.E * (sec.Iy if _PLANES[plane] == "flatwise" else sec.Iz)
        return (omega**2 * self.rho * sec.A * self.length**4 / EI) ** 0.25

    def mode_details(self, n_modes: int) -> dict:
        """Exact vs FE βL in both bending planes (as many modes as tabulated), JSON-ready."""
        require_count(n_modes, "n_modes")
        exact = self.exact_beta_L
        k = len(exact)
        out = {"beta_L_exact": exact.tolist()}
        for plane in ("flatwise", "edgewise"):
            f, family, _ = self._solve(4 * k + 8)
            m = min(k, int(np.sum(family == plane)))  # a very coarse mesh may have fewer
            fe = self.beta_L(m, plane) if m else np.zeros(0)
            out[f"beta_L_{plane}"] = fe.tolist()
            out[f"beta_L_{plane}_rel_error"] = (fe / exact[:m] - 1.0).tolist()
            out[f"{plane}_hz"] = f[family == plane][:m].tolist()
        return out


def _beam(boundary: str, builder: str, overrides: dict[str, Any]) -> BeamCase:
    return BeamCase(boundary=boundary, **read_inputs(builder, _BEAM_INPUTS, overrides))


def cantilever_beam(**overrides: Any) -> BeamCase:
    """Uniform cantilever (clamped at x = 0); override ``length``, ``E``, ``rho``, ``nu``,
    ``width``, ``height`` (numbers in SI or unit strings), ``n_elements``, ``lumped``.

    >>> cantilever_beam(length="2 m", n_elements=40).beta_L(3)  # doctest: +SKIP
    """
    return _beam("cantilever", "cantilever_beam", overrides)


def free_free_beam(**overrides: Any) -> BeamCase:
    """Uniform free-free beam (6 rigid-body modes dropped); same overrides as
    :func:`cantilever_beam`."""
    return _beam("free-free", "free_free_beam", overrides)


# ------------------------------------------------------------------------------------------------
# NAFEMS FV2
_FV2_PLANES = ("in-plane", "3d")
_FV2_INPUTS = {
    "arm_length": Param(PUBLISHED["fv2_arm_length"], "m"),
    "side": Param(PUBLISHED["fv2_side"], "m"),
    "E": Param(PUBLISHED["fv2_modulus"], "Pa"),
    "rho": Param(PUBLISHED["fv2_density"], "kg/m**3"),
    "nu": Param(0.3, rule=_poisson),
    "elements_per_arm": Param(4, rule="count", limit="MAX_ELEMENTS"),
    "lumped": Param(False, rule="flag"),
    "plane": Param("in-plane", rule="choice", choices=_FV2_PLANES),
}
N_ARMS = 8


@dataclass(frozen=True)
class Fv2Case:
    """NAFEMS FV2 pin-ended double cross (eight 5 m arms at 45°, node 0 at the centre)."""

    arm_length: float
    side: float
    E: float
    rho: float
    nu: float
    elements_per_arm: int
    lumped: bool
    plane: str
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def tip_nodes(self) -> list[int]:
        """Node ids of the eight pinned arm tips (arm k at angle 45° k: id 100 (k+1) + n)."""
        return [100 * (k + 1) + self.elements_per_arm for k in range(N_ARMS)]

    def structure(self) -> Structure:
        mat = Material(E=self.E, rho=self.rho, nu=self.nu, name="steel")
        sec = Section.rectangle(self.side, self.side, name="square")
        s = Structure("NAFEMS FV2 pin-ended double cross")
        s.add_node(0, (0.0, 0.0, 0.0))
        n = self.elements_per_arm
        for k in range(N_ARMS):
            a = np.pi / 4 * k
            u = np.array([np.cos(a), np.sin(a), 0.0])
            prev = 0
            for j in range(1, n + 1):
                nid = 100 * (k + 1) + j
                s.add_node(nid, self.arm_length * j / n * u)
                if self.plane == "3d":
                    s.add_frame(prev, nid, mat, sec, lumped=self.lumped, label=f"arm {k + 1}")
                else:
                    s.add_beam2d(prev, nid, mat, sec, lumped=self.lumped, label=f"arm {k + 1}")
                prev = nid
            s.clamp(prev, ("ux", "uy", "uz") if self.plane == "3d" else ("ux", "uy"))
        return s

    def plant(self, n_modes: int = 8, damping: float = 0.01) -> StructuralPlant:
        """The cross as a plant: a force ``force`` at the mid-point of arm 1 (along x) across
        the arm (along y, in the plane of the in-plane model, the benchmark's), the
        displacements there and at the centre node 0, on the modal model of its first
        ``n_modes`` modes with ``damping`` on each."""
        from flexsat.cases.structure_plants import first_modes, point_force_plant

        if self.plane != "in-plane":
            # pinned tips with free rotations: no rigid-mass split a ModalModel can carry
            raise FieldError(
                "plane",
                "the plant is built on the in-plane model (plane 'in-plane', the benchmark's)",
            )
        mid = 100 + self.elements_per_arm // 2
        return point_force_plant(
            first_modes(self.structure(), n_modes), mid, [mid, 0], "y", damping
        )

    def _frequencies(self) -> np.ndarray:
        if "f" not in self._cache:
            asm = self.structure().assemble()
            modes = asm.modes(min(len(asm.dofs), 40))
            self._cache["f"] = modes.omegas / (2 * np.pi)
        return self._cache["f"]

    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        n = require_count(n_modes, "n_modes")
        f = self._frequencies()
        if n > len(f):
            raise FieldError("n_modes", f"at most {len(f)} modes are computed, got {n}")
        return f[:n].copy()

    def mode_details(self, n_modes: int) -> dict:
        """The 16 NAFEMS reference frequencies vs the model's first 16 (Hz, relative error)."""
        require_count(n_modes, "n_modes")
        f = self.frequencies_hz(len(FV2_REFERENCE_HZ))
        return {
            "reference_hz": FV2_REFERENCE_HZ.tolist(),
            "computed_hz": f.tolist(),
            "rel_error": (f / FV2_REFERENCE_HZ - 1.0).tolist(),
        }


def nafems_fv2(**overrides: Any) -> Fv2Case:
    """NAFEMS FV2 double cross; override ``arm_length``, ``side``, ``E``, ``rho``, ``nu`` (SI
    numbers or unit strings), ``elements_per_arm``, ``lumped`` and ``plane`` ("in-plane", the
    benchmark, or "3d": frames pinned in x, y, z at the tips)."""
    return Fv2Case(**read_inputs("nafems_fv2", _FV2_INPUTS, overrides))
