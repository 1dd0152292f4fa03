r"""A design problem on your own finite-element model: section dimensions and lumped masses as
design variables, structural mass and natural frequencies as responses, analytic gradients.

The model is an :class:`~flexsat.structures.fe_description.FEDescription` (SI; the inline
``model: {fe: ...}`` section of a scenario builds one). A design variable names

- a **section** of the description and one of its dimensions (:data:`SECTION_PROPERTIES`): every
  member using that section is one design group, changed together (a tube's wall or outer
  diameter, a rectangle's width or height, a circle's diameter, a general section's area, Iy,
  Iz or J);
- a **material** of the description and its Young's modulus ``E`` or its ``density``, in every
  member made of it; or
- a **lumped mass** of the description (by its index) and its ``mass`` or its principal
  ``inertia`` about a global axis.

Responses, each with its analytic gradient with respect to every variable (SI):

- ``mass``: structural mass (members Σ ρ A L and lumped masses), kg;
- ``frequency_hz_<k>``: the k-th elastic natural frequency, Hz (k = 1 the lowest; the six
  rigid-body modes of a free structure are not counted);
- ``separation_hz_<i>_<j>``: f_j − f_i, Hz, i < j.

Gradients: ∂K/∂p, ∂M/∂p of each variable from the element matrices
(:func:`flexsat.analysis.fe_sensitivity.fe_parameter_matrices`: exact, the element matrices are
affine in the section properties, chained through the section formulas), the eigenvalue
derivative ∂λ/∂p = φᵀ(∂K/∂p − λ ∂M/∂p)φ (Fox & Kapoor, "Rates of change of eigenvalues and
eigenvectors", AIAA J. 6(12), 2426-2429, 1968) and ∂f/∂p = (∂λ/∂p) / (4π² · 2f)
(:func:`flexsat.analysis.fe_sensitivity.fe_modal_derivatives`; the mode shapes' Nelson
derivatives are computed there too). A variable acting on several kinds of design parameter
(a circle's diameter moves a tube's diameter and wall together; a section used by frames and
rods) is the sum of their derivatives with the chain coefficients, exact because ∂K and ∂M
are linear in the parameter directions.

Rigid-body modes of a free structure stay at ω = 0 for every design (rigid motions are null
vectors of every ∂K), so they are neither responses nor differentiated
(docs/design_gradients.md).

**Mode order, not mode tracking.** ``frequency_hz_k`` is the k-th lowest elastic frequency at
each design. It is continuous in the design, and differentiable wherever that frequency is
simple; where two modes swap order (a crossing), the k-th frequency has a kink and no gradient:
an evaluation at a repeated frequency (λ gap <= ``gap_rtol`` · λ_max) is refused naming both
modes. A frequency floor on mode 1 is then a floor on the lowest frequency whichever mode
shape it has (what a requirement means), and a separation constraint f_{k+1} − f_k >= Δ > 0
keeps the two modes from crossing. :meth:`StructureProblem.report_metrics` says, for each
response mode at a design, which mode of the start design it is (largest modal assurance
criterion, MAC = (φᵀψ)² / (φᵀφ · ψᵀψ), Allemang & Brown, "A correlation coefficient for modal
vector analysis", Proc. 1st International Modal Analysis Conference, 110-116, 1982): a swap
shows as mode k matching another start mode.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from flexsat.analysis.fe_sensitivity import (
    DesignParameter,
    LumpedInertia,
    LumpedMass,
    MemberProperty,
    RectangleSection,
    TubeSection,
    fe_modal_derivatives,
    fe_parameter_matrices,
    rectangle_section_derivatives,
    tube_section_derivatives,
)
from flexsat.analysis.sensitivity import GAP_RTOL
from flexsat.design.describe import DesignFeature
from flexsat.design.optimization_problem import (
    Constraint,
    DesignProblem,
    DesignVariable,
    Objective,
)
from flexsat.input_checks import FieldError, require_physical_inertia
from flexsat.structures.fe_description import FEDescription, MassSpec
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Section
from flexsat.units import FloatArray

__all__ = [
    "MASS_PROPERTIES",
    "MATERIAL_PROPERTIES",
    "PROPERTY_UNITS",
    "SECTION_PROPERTIES",
    "MassVariable",
    "MaterialVariable",
    "SectionShape",
    "SectionVariable",
    "StructureProblem",
    "parse_response",
]

#: the dimensions of each section shape a variable may name (Section's constructors)
SECTION_PROPERTIES = {
    "tube": ("outer_diameter", "thickness"),
    "circle": ("diameter",),
    "rectangle": ("width", "height"),
    "general": ("area", "Iy", "Iz", "J"),
}
#: the properties of a lumped mass a variable may name
MASS_PROPERTIES = ("mass", "inertia")
#: the properties of a material a variable may name (and the member quantity each moves)
MATERIAL_PROPERTIES = {"E": "E", "density": "rho"}
#: SI unit of each property
PROPERTY_UNITS = {
    "outer_diameter": "m",
    "thickness": "m",
    "diameter": "m",
    "width": "m",
    "height": "m",
    "area": "m**2",
    "Iy": "m**4",
    "Iz": "m**4",
    "J": "m**4",
    "mass": "kg",
    "inertia": "kg*m**2",
    "E": "Pa",
    "density": "kg/m**3",
}
_AXES = ("x", "y", "z")
_RESPONSE = re.compile(r"^(?:(mass)|frequency_hz_(\d+)|separation_hz_(\d+)_(\d+))$")
#: free 3-D structure
_RIGID_MODES = 6


@dataclass(frozen=True)
class SectionShape:
    """The shape of a section of the description and its current dimensions (SI), as
    :data:`SECTION_PROPERTIES` names them (``{"outer_diameter": 0.03, "thickness": 1e-3}``)."""

    shape: str
    dimensions: Mapping[str, float]

    def section(self, values: Mapping[str, float]) -> Section:
        """The section with ``values`` replacing some of its dimensions."""
        d = {**self.dimensions, **values}
        if self.shape == "tube":
            return Section.tube(d["outer_diameter"], d["thickness"])
        if self.shape == "circle":
            return Section.circle(d["diameter"])
        if self.shape == "rectangle":
            return Section.rectangle(d["width"], d["height"])
        return Section.general(d["area"], d["Iy"], d["Iz"], d["J"])


@dataclass(frozen=True)
class SectionVariable:
    """A dimension ``property`` of the members using section ``section`` (SI bounds)."""

    name: str
    section: str
    property: str
    start: float
    lower: float
    upper: float


@dataclass(frozen=True)
class MassVariable:
    """The ``mass`` (kg) or principal ``inertia`` about ``axis`` (kg m²) of lumped mass
    ``masses[index]`` of the description (SI bounds)."""

    name: str
    index: int
    property: str
    start: float
    lower: float
    upper: float
    axis: str | None = None


@dataclass(frozen=True)
class MaterialVariable:
    """Young's modulus ``E`` (Pa) or ``density`` (kg/m³) of material ``material`` in every
    member made of it (SI bounds); with ν given and no explicit G, G = E / (2 (1 + ν)) follows E
    (as :meth:`~flexsat.structures.fem.Structure.property_derivative` differentiates it)."""

    name: str
    material: str
    property: str
    start: float
    lower: float
    upper: float


Variable = SectionVariable | MassVariable | MaterialVariable


def parse_response(name: str) -> tuple[str, tuple[int, ...]]:
    """``("mass", ())``, ``("frequency_hz", (k,))`` or ``("separation_hz", (i, j))`` of a
    response name (module docstring); a name that is none of them is refused."""
    match = _RESPONSE.match(name) if isinstance(name, str) else None
    if match is None:
        raise FieldError(
            "response",
            f"{name!r} is not a response of a model: mass, frequency_hz_<k> (k-th elastic "
            "mode, 1 the lowest) or separation_hz_<i>_<j> (f_j - f_i, i < j)",
        )
    if match.group(1):
        return "mass", ()
    if match.group(2):
        k = int(match.group(2))
        if k < 1:
            raise FieldError("response", f"{name}: modes count from 1 (the lowest elastic)")
        return "frequency_hz", (k,)
    i, j = int(match.group(3)), int(match.group(4))
    if not 1 <= i < j:
        raise FieldError("response", f"{name}: separation_hz_<i>_<j> needs 1 <= i < j")
    return "separation_hz", (i, j)


@dataclass(frozen=True)
class StructureProblem:
    """Design variables on an FE description and its mass and frequency responses (module
    docstring). Picklable (dask workers of a Pareto front).

    Attributes
    ----------
    description : FEDescription
        The model (SI); its ``n_modes`` bounds the mode numbers a response may name.
    shapes : mapping of str to SectionShape
        Shape and dimensions of every section a variable names.
    variables : tuple of SectionVariable and MassVariable
    responses_named : tuple of str
        Responses to compute (``mass`` is always computed).
    gap_rtol : float
        Frequencies closer than this times λ_max count as repeated (no derivative).
    """

    description: FEDescription
    shapes: Mapping[str, SectionShape]
    variables: tuple[Variable, ...]
    responses_named: tuple[str, ...] = ("mass",)
    gap_rtol: float = GAP_RTOL
    _memo: dict[bytes, dict[str, tuple[float, FloatArray]]] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )
    _start: dict[str, FloatArray] = field(
        default_factory=dict, init=False, repr=False, compare=False
    )

    def __post_init__(self) -> None:
        if not self.variables:
            raise FieldError("variables", "name at least one design variable")
        names = [v.name for v in self.variables]
        for name in names:
            if names.count(name) > 1:
                raise FieldError("variables", f"duplicate variable {name!r}")
        targets: dict[tuple[object, ...], str] = {}
        for v in self.variables:
            key = self._check_variable(v)
            if key in targets:
                raise FieldError(
                    f"variables.{v.name}", f"acts on what {targets[key]!r} already varies"
                )
            targets[key] = v.name
        self._check_box()
        for name in self.responses_named:
            _, modes = parse_response(name)
            if modes and max(modes) > self.description.n_modes:
                raise FieldError(
                    name,
                    f"mode {max(modes)} is beyond the model's n_modes = "
                    f"{self.description.n_modes} elastic modes (raise model.fe.n_modes)",
                )

    # -- checks --------------------------------------------------------------------------------
    def _check_variable(self, v: Variable) -> tuple[object, ...]:
        where = f"variables.{v.name}"
        for key in ("start", "lower", "upper"):
            value = getattr(v, key)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise FieldError(f"{where}.{key}", f"must be finite and > 0, got {value!r}")
        if not v.lower < v.upper:
            raise FieldError(f"{where}.lower", f"must be < upper, got [{v.lower}, {v.upper}]")
        if not v.lower <= v.start <= v.upper:
            raise FieldError(f"{where}.start", f"{v.start} is outside [{v.lower}, {v.upper}]")
        if isinstance(v, SectionVariable):
            if v.section not in self.shapes:
                raise FieldError(f"{where}.section", f"unknown section {v.section!r}")
            shape = self.shapes[v.section].shape
            if v.property not in SECTION_PROPERTIES.get(shape, ()):
                raise FieldError(
                    f"{where}.property",
                    f"a {shape} section has {', '.join(SECTION_PROPERTIES.get(shape, ()))}; "
                    f"got {v.property!r}",
                )
            if not self._members(v.section)[0] and not self._members(v.section)[1]:
                raise FieldError(f"{where}.section", f"no element uses section {v.section!r}")
            if v.property in ("Iy", "Iz", "J") and not self._members(v.section)[0]:
                raise FieldError(
                    f"{where}.property", f"{v.property} acts on frames; {v.section!r} has rods only"
                )
            return ("section", v.section, v.property)
        if isinstance(v, MaterialVariable):
            if v.material not in self.description.materials:
                raise FieldError(f"{where}.material", f"unknown material {v.material!r}")
            if v.property not in MATERIAL_PROPERTIES:
                raise FieldError(f"{where}.property", f"must be E or density, got {v.property!r}")
            if not self._made_of(v.material):
                raise FieldError(f"{where}.material", f"no element is made of {v.material!r}")
            return ("material", v.material, v.property)
        if not 0 <= v.index < len(self.description.masses):
            raise FieldError(f"{where}.mass", f"no lumped mass {v.index}")
        if v.property not in MASS_PROPERTIES:
            raise FieldError(f"{where}.property", f"must be mass or inertia, got {v.property!r}")
        if (v.property == "inertia") != (v.axis is not None):
            raise FieldError(f"{where}.axis", "an inertia names its axis (x, y, z); a mass none")
        if v.axis is not None and v.axis not in _AXES:
            raise FieldError(f"{where}.axis", f"must be x, y or z, got {v.axis!r}")
        return ("mass", v.index, v.property, v.axis)

    def _check_box(self) -> None:
        """Every design in the bounds builds a valid model: a tube's wall at most half its
        outer diameter at the worst corner; an inertia a body has at every corner (the set of
        physical inertias is convex, so its corners suffice)."""
        for key, shape in self.shapes.items():
            vs = {v.property: v for v in self._section_variables(key)}
            if shape.shape == "tube" and vs:
                t = vs["thickness"].upper if "thickness" in vs else shape.dimensions["thickness"]
                D = (
                    vs["outer_diameter"].lower
                    if "outer_diameter" in vs
                    else shape.dimensions["outer_diameter"]
                )
                if 2 * t > D:
                    worst = vs.get("thickness") or vs["outer_diameter"]
                    bound = "upper" if worst.property == "thickness" else "lower"
                    raise FieldError(
                        f"variables.{worst.name}.{bound}",
                        f"the wall must stay <= half the outer diameter over the bounds: "
                        f"largest wall {t:g} m, smallest diameter {D:g} m",
                    )
        for index, spec in enumerate(self.description.masses):
            inertia = [v for v in self._mass_variables(index) if v.property == "inertia"]
            if not inertia:
                continue
            base = np.zeros((3, 3)) if spec.inertia is None else np.asarray(spec.inertia, float)
            base = np.diag(base) if base.ndim == 1 else base
            for corner in itertools.product(*((v.lower, v.upper) for v in inertia)):
                J = base.copy()
                for v, value in zip(inertia, corner):
                    a = _AXES.index(str(v.axis))
                    J[a, a] = value
                require_physical_inertia(J, f"variables.{inertia[0].name}.lower", False)

    def _members(self, section: str) -> tuple[tuple[int, ...], tuple[int, ...]]:
        """Element ids (frames, rods) using ``section`` (ids are the description's order)."""
        elements = self.description.elements
        frames = tuple(
            i for i, e in enumerate(elements) if e.section == section and e.kind == "frame"
        )
        rods = tuple(i for i, e in enumerate(elements) if e.section == section and e.kind == "rod")
        return frames, rods

    def _made_of(self, material: str) -> tuple[int, ...]:
        """Element ids made of ``material``."""
        return tuple(i for i, e in enumerate(self.description.elements) if e.material == material)

    def _section_variables(self, section: str) -> list[SectionVariable]:
        return [
            v for v in self.variables if isinstance(v, SectionVariable) and v.section == section
        ]

    def _mass_variables(self, index: int) -> list[MassVariable]:
        return [v for v in self.variables if isinstance(v, MassVariable) and v.index == index]

    # -- the model at a design -----------------------------------------------------------------
    @property
    def names(self) -> tuple[str, ...]:
        return tuple(v.name for v in self.variables)

    @property
    def x0(self) -> FloatArray:
        return np.array([v.start for v in self.variables])

    @property
    def free(self) -> bool:
        return self.description.free

    def description_at(self, x: Sequence[float] | FloatArray) -> FEDescription:
        """The description with the design ``x`` (SI, in the order of the variables)."""
        values = dict(zip(self.names, np.asarray(x, dtype=float).tolist()))
        sections = dict(self.description.sections)
        for key, shape in self.shapes.items():
            changed = {v.property: values[v.name] for v in self._section_variables(key)}
            if changed:
                sections[key] = shape.section(changed)
        materials = dict(self.description.materials)
        for v in self.variables:
            if isinstance(v, MaterialVariable):
                field_name = "E" if v.property == "E" else "rho"
                materials[v.material] = dataclasses.replace(
                    materials[v.material], **{field_name: values[v.name]}
                )
        masses = list(self.description.masses)
        for index, spec in enumerate(masses):
            vs = self._mass_variables(index)
            if not vs:
                continue
            mass, inertia = spec.mass, spec.inertia
            for v in vs:
                if v.property == "mass":
                    mass = values[v.name]
                else:
                    J = np.zeros(3) if inertia is None else np.asarray(inertia, float).copy()
                    a = _AXES.index(str(v.axis))
                    if J.ndim == 1:
                        J[a] = values[v.name]
                    else:
                        J[a, a] = values[v.name]
                    inertia = J
            masses[index] = MassSpec(spec.node, mass, inertia, spec.offset)
        return dataclasses.replace(
            self.description, sections=sections, masses=masses, materials=materials
        )

    def structure(self, x: Sequence[float] | FloatArray) -> Structure:
        """The :class:`~flexsat.structures.fem.Structure` at design ``x``."""
        return self.description_at(x).structure()

    def parameters(
        self, x: Sequence[float] | FloatArray
    ) -> tuple[list[DesignParameter], FloatArray]:
        """The FE design parameters at ``x`` and the chain matrix C (variables × parameters):
        ∂(·)/∂x_v = Σ_p C[v, p] ∂(·)/∂p (module docstring)."""
        values = dict(zip(self.names, np.asarray(x, dtype=float).tolist()))
        params: list[DesignParameter] = []
        rows: list[list[tuple[int, float]]] = []
        for v in self.variables:
            row: list[tuple[int, float]] = []

            def add(
                param: DesignParameter,
                coefficient: float,
                row: list[tuple[int, float]] = row,
            ) -> None:
                row.append((len(params), coefficient))
                params.append(param)

            if isinstance(v, MaterialVariable):
                quantity = MATERIAL_PROPERTIES[v.property]
                add(MemberProperty(quantity, self._made_of(v.material)), 1.0)
            elif isinstance(v, MassVariable):
                spec = self.description.masses[v.index]
                if v.property == "mass":
                    offset = None if spec.offset is None else _triple(spec.offset)
                    add(LumpedMass(spec.node, offset), 1.0)
                else:
                    add(LumpedInertia(spec.node, str(v.axis)), 1.0)
            else:
                self._section_parameters(v, values, add)
            rows.append(row)
        C = np.zeros((len(self.variables), len(params)))
        for i, row in enumerate(rows):
            for p, c in row:
                C[i, p] = c
        return params, C

    def _section_parameters(
        self,
        v: SectionVariable,
        values: Mapping[str, float],
        add: Callable[[DesignParameter, float], None],
    ) -> None:
        shape = self.shapes[v.section]
        dims = {**shape.dimensions}
        dims.update({w.property: values[w.name] for w in self._section_variables(v.section)})
        frames, rods = self._members(v.section)
        if shape.shape == "tube":
            D, t = dims["outer_diameter"], dims["thickness"]
            if frames:
                add(TubeSection(v.property, frames, D, t), 1.0)
            if rods:
                add(MemberProperty("A", rods), float(tube_section_derivatives(D, t)[v.property][0]))
        elif shape.shape == "circle":
            D = dims["diameter"]
            if frames:  # a solid circle is the tube (D, D/2): d/dD = ∂/∂D + ½ ∂/∂t
                add(TubeSection("outer_diameter", frames, D, D / 2), 1.0)
                add(TubeSection("thickness", frames, D, D / 2), 0.5)
            if rods:
                add(MemberProperty("A", rods), math.pi * D / 2)
        elif shape.shape == "rectangle":
            b, h = dims["width"], dims["height"]
            if frames:
                add(RectangleSection(v.property, frames, b, h), 1.0)
            if rods:
                add(
                    MemberProperty("A", rods),
                    float(rectangle_section_derivatives(b, h)[v.property][0]),
                )
        else:
            quantity = {"area": "A"}.get(v.property, v.property)
            add(MemberProperty(quantity, frames + rods if quantity == "A" else frames), 1.0)

    # -- responses -----------------------------------------------------------------------------
    def modes_named(self) -> tuple[int, ...]:
        """Elastic mode numbers (1 = lowest) the responses need, ascending."""
        modes: set[int] = set()
        for name in self.responses_named:
            modes.update(parse_response(name)[1])
        return tuple(sorted(modes))

    def response_units(self) -> dict[str, str]:
        """SI unit of every response :meth:`responses` returns."""
        units = {"mass": "kg"}
        units.update({f"frequency_hz_{k}": "Hz" for k in self.modes_named()})
        units.update({n: "Hz" for n in self.responses_named if n.startswith("separation_hz_")})
        return units

    def responses(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        """Every response (:meth:`response_units`) and its gradient (n,) at ``x``, SI."""
        key = np.asarray(x, dtype=float).tobytes()
        if key not in self._memo:
            self._memo.clear()
            self._memo[key] = self._evaluate(np.asarray(x, dtype=float))
        return self._memo[key]

    def _rigid(self) -> int | None:
        return _RIGID_MODES if self.free else None

    def _evaluate(self, x: FloatArray) -> dict[str, tuple[float, FloatArray]]:
        structure = self.structure(x)
        params, C = self.parameters(x)
        out: dict[str, tuple[float, FloatArray]] = {}
        modes = self.modes_named()
        if not modes:
            mats = fe_parameter_matrices(structure, params)
            out["mass"] = (mats.mass, C @ mats.mass_gradient)
            return out
        shift = (self._rigid() or 0) - 1
        try:
            d = fe_modal_derivatives(
                structure,
                params,
                [k + shift for k in modes],
                rigid_body_modes=self._rigid(),
                gap_rtol=self.gap_rtol,
            )
        except FieldError as exc:
            if exc.field != "modes":
                raise
            raise self._crossing(structure, x, max(modes)) from None
        out["mass"] = (float(d.mass), C @ d.mass_gradient)
        f, df = d.frequencies_hz, C @ d.frequency_hz_gradient
        col = {k: i for i, k in enumerate(modes)}
        for k in modes:
            out[f"frequency_hz_{k}"] = (float(f[col[k]]), df[:, col[k]])
        for name in self.responses_named:
            kind, pair = parse_response(name)
            if kind == "separation_hz":
                i, j = col[pair[0]], col[pair[1]]
                out[name] = (float(f[j] - f[i]), df[:, j] - df[:, i])
        return out

    def _crossing(self, structure: Structure, x: FloatArray, top: int) -> FieldError:
        """The refusal of a design where two elastic modes coincide (numbered from 1)."""
        asm = structure.assemble()
        rigid = self._rigid() or 0
        f = asm.modes(min(rigid + top + 1, asm.n_dofs), rigid_body_modes=self._rigid())
        elastic = f.frequencies_hz[rigid:]
        k = int(np.argmin(np.diff(elastic))) + 1
        return FieldError(
            "model",
            f"at the design {dict(zip(self.names, x.tolist()))}: elastic modes {k} and {k + 1} "
            f"coincide (f = {elastic[k - 1]:.6g} and {elastic[k]:.6g} Hz), a crossing where "
            f"the k-th frequency has no derivative; a constraint separation_hz_{k}_{k + 1} >= "
            "a margin keeps them apart",
        )

    # -- mode tracking -------------------------------------------------------------------------
    def _modes(self, x: FloatArray, count: int) -> FloatArray:
        asm = self.structure(x).assemble()
        rigid = self._rigid() or 0
        count = min(count + rigid, asm.n_dofs)
        return asm.modes(count, rigid_body_modes=self._rigid()).shapes[:, rigid:]

    def report_metrics(self, x: FloatArray) -> dict[str, float]:
        """For each response mode k at ``x``: ``mode_k_is_start_mode`` (the mode of the start
        design it resembles most, by MAC, among the start's lowest k + 3) and ``mode_k_mac``."""
        modes = self.modes_named()
        if not modes:
            return {}
        count = min(max(modes) + 3, self.description.n_modes)
        if "shapes" not in self._start:
            self._start["shapes"] = self._modes(self.x0, count)
        start = self._start["shapes"]
        now = self._modes(np.asarray(x, dtype=float), max(modes))
        out: dict[str, float] = {}
        for k in modes:
            phi = now[:, k - 1]
            mac = (start.T @ phi) ** 2 / (np.sum(start**2, axis=0) * (phi @ phi))
            best = int(np.argmax(mac))
            out[f"mode_{k}_is_start_mode"] = float(best + 1)
            out[f"mode_{k}_mac"] = float(mac[best])
        return out

    def describe(self, x: FloatArray) -> dict[str, DesignFeature]:
        """The design ``x`` as a structure, for the report's start-beside-final table: the
        model's ``n_modes`` elastic frequencies (Hz) and its structural mass (kg)."""
        structure = self.structure(np.asarray(x, dtype=float))
        asm = structure.assemble()
        rigid = self._rigid() or 0
        count = min(rigid + self.description.n_modes, asm.n_dofs)
        f = asm.modes(count, rigid_body_modes=self._rigid()).frequencies_hz[rigid:]
        return {
            "elastic frequencies": DesignFeature(
                "structure",
                f,
                "Hz",
                labels=tuple(f"mode {k + 1}" for k in range(f.size)),
                note="modal solve of the finite-element model at the design (ascending; the "
                "rigid-body modes of a free model are not listed)",
            ),
            "structural mass": DesignFeature(
                "structure",
                np.array([structure.structural_mass()]),
                "kg",
                note="members Σ ρ A L and lumped masses",
            ),
        }

    # -- as a DesignProblem --------------------------------------------------------------------
    def problem(
        self,
        objective: str = "mass",
        constraints: Sequence[tuple[str, float | None, float | None]] = (),
    ) -> DesignProblem:
        """Minimise ``objective`` subject to ``min <= response <= max`` for each
        ``(response, min, max)`` of ``constraints`` (SI, None: no bound), within the
        variables' bounds; scaled by the start values and the bounds."""
        units = self.response_units()
        for name in (objective, *(c[0] for c in constraints)):
            if name not in units:
                raise FieldError("response", f"{name!r} is not among {', '.join(units)}")
        variables = tuple(
            DesignVariable(v.name, v.start, v.lower, v.upper, scale=v.start, unit=_unit(v))
            for v in self.variables
        )
        r0 = self.responses(self.x0)

        def response(
            name: str, sign: float, offset: float
        ) -> Callable[[FloatArray], tuple[float, FloatArray]]:
            def value(x: FloatArray) -> tuple[float, FloatArray]:
                v, g = self.responses(x)[name]
                return sign * (v - offset), sign * g

            return value

        cons = []
        for name, lo, hi in constraints:
            for bound, sign, label in ((lo, -1.0, ">="), (hi, 1.0, "<=")):
                if bound is not None:
                    cons.append(
                        Constraint(
                            f"{name} {label} {bound:.6g}",
                            response(name, sign, bound),
                            scale=abs(bound) or abs(r0[name][0]) or 1.0,
                            unit=units[name],
                        )
                    )
        return DesignProblem(
            variables,
            Objective(
                objective,
                response(objective, 1.0, 0.0),
                scale=abs(r0[objective][0]) or 1.0,
                unit=units[objective],
            ),
            tuple(cons),
        )


def _triple(value: object) -> tuple[float, float, float]:
    a, b, c = np.asarray(value, dtype=float).reshape(3).tolist()
    return float(a), float(b), float(c)


def _unit(v: Variable) -> str:
    return PROPERTY_UNITS[v.property]
