"""The ``model:`` section of a simulation scenario: your own structure instead of a published case.

Exactly one of ``case:`` (a built-in system) and ``model:`` is given. ``model:`` takes one of

- ``file:`` a modal model on disk, read by its suffix: ``.nc`` a
  :class:`~flexsat.structures.modal_model.ModalModel` netCDF file (:meth:`ModalModel.save`);
  ``.op2`` NASTRAN (:func:`~flexsat.structures.io_nastran.read_nastran_modes`, with ``op4:``,
  ``superelement:`` and the model's ``units:``); ``.uff``/``.unv`` a universal file
  (:func:`~flexsat.structures.io_uff.modal_model_from_uff`). ``damping:`` (a modal ratio, or one
  per mode) and ``reference:`` apply to NASTRAN and UFF files; a universal file or a plain
  SOL 103 OP2 holds no mass matrix, so one without six rigid-body modes (a constrained
  structure) takes ``participation:`` (modes x 6) and, for a UFF (an OP2 has its OGPWG),
  ``rigid_mass:`` (6x6), plain SI numbers (kg, kg m, kg m², √kg, √kg m) about ``reference``.
  A relative path starts at the scenario file's folder;
- ``fe:`` an inline finite-element description: ``nodes`` (``id``, ``xyz``), ``materials``
  (``E``, ``G`` or ``nu``, ``density``), ``sections`` (``area``, ``Iy``, ``Iz``, ``J``, or a
  ``shape`` of :class:`~flexsat.structures.sections.Section`: ``tube``, ``circle``,
  ``rectangle``), ``elements`` (``frame`` or ``rod`` members between two nodes naming their
  material and section, a frame's ``orientation`` vector and end ``offsets``), ``masses``
  (``mass``, ``inertia`` about its own centre, rigid ``offset`` from its node), ``rigid_links``
  (``node`` and the ``nodes`` tied rigidly to it, an RBE2), ``clamps``
  (``node``, ``dofs``: ``all`` or a list of ux, uy, uz, rx, ry, rz; none: free-free),
  ``n_modes`` (elastic modes) and modal ``damping``, built by
  :class:`~flexsat.structures.fe_description.FEDescription`;
- ``hub_appendage:`` a rigid hub with identical cantilevered appendages from its parameters
  (:class:`~flexsat.dynamics.hub_appendage.HubAppendageParams`).

The plant follows from the model: a free-free modal model is a three-axis
:class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft` (``plant:`` options
``n_modes``, ``torque_node``, ``forces``, ``displacements``, ``rotations`` as ``[node, axis]``
pairs, ``translation``), or with ``rigid: true`` the same body as a
:class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` (its inertia about its centre of
mass); a constrained one a
:class:`~flexsat.dynamics.structural.StructuralPlant` (``n_modes``, ``actuators`` and
``sensors`` naming their node and axis); a hub with appendages a single-axis
:class:`~flexsat.dynamics.hub_appendage.HubAppendage` (``n_modes`` per appendage,
``stiffening``). Quantities take units like every scenario field; a problem is reported at its
field path (``model.fe.elements[3].section: unknown section 'boom'``).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, Literal, Self

import numpy as np
from pydantic import BeforeValidator, Field, ValidationInfo, model_validator

from flexsat import limits
from flexsat.input_checks import FieldError, require_finite
from flexsat.scenarios.fields import BuildableSection, SchemaSection, in_unit, integer_in
from flexsat.units import to_si_array

if TYPE_CHECKING:
    from flexsat.dynamics.hub_appendage import HubAppendageParams
    from flexsat.dynamics.plant import Plant
    from flexsat.structures.fe_description import FEDescription
    from flexsat.structures.modal_model import ModalModel

__all__ = ["ModelPlantOptions", "ModelSection", "model_label", "model_plant"]

_NODE = Annotated[int, integer_in(-(2**31), 2**31 - 1)]
_MAX_ENTRIES = limits.MAX_SAMPLES
#: file suffixes and the reader each one takes
FILE_KINDS = {".nc": "netcdf", ".op2": "nastran", ".uff": "uff", ".unv": "uff"}


def _array_in(unit: str, shapes: tuple[tuple[int, ...], ...]) -> BeforeValidator:
    """Validator of an array field in ``unit`` (a list of numbers or quantities, SI stored as a
    nested list) with one of ``shapes``."""

    def convert(value: Any, info: ValidationInfo) -> Any:
        if value is None:
            return None
        field = info.field_name or ""
        if isinstance(value, (bool, str)) or not isinstance(value, (list, tuple)):
            raise FieldError(field, f"a list of {_shapes_text(shapes)} values, got {value!r}")
        si = require_finite(to_si_array(value, unit, field), field)
        if si.shape not in shapes:
            raise FieldError(
                field, f"must have {_shapes_text(shapes)} values, got shape {si.shape}"
            )
        return si.tolist()

    return BeforeValidator(convert)


def _shapes_text(shapes: tuple[tuple[int, ...], ...]) -> str:
    return " or ".join("x".join(map(str, s)) for s in shapes)


Vector = Annotated[list[float] | None, _array_in("m", ((3,),))]
Direction = Annotated[list[float] | None, _array_in("", ((3,),))]
Offsets = Annotated[list[list[float]] | None, _array_in("m", ((2, 3),))]
Inertia = Annotated[Any, _array_in("kg*m**2", ((3,), (3, 3)))]


def _ratios(value: Any, info: ValidationInfo) -> Any:
    """A modal damping ratio, or a list of them (one per mode), each >= 0."""
    if value is None:
        return None
    field = info.field_name or "damping"
    if isinstance(value, bool):
        raise FieldError(field, f"a damping ratio or a list of them, got {value!r}")
    zeta = require_finite(to_si_array(value, "", field), field)
    if zeta.ndim > 1 or np.any(zeta < 0):
        raise FieldError(field, f"ratios >= 0, one or one per mode, got {value!r}")
    return float(zeta) if zeta.ndim == 0 else zeta.tolist()


Damping = Annotated[Any, BeforeValidator(_ratios)]


def _si_matrix(value: Any, info: ValidationInfo) -> Any:
    """A matrix of plain SI numbers with six columns (a rigid mass, a participation)."""
    if value is None:
        return None
    field = info.field_name or ""
    try:
        matrix = require_finite(value, field)
    except FieldError:
        raise FieldError(field, "a list of rows of six plain numbers in SI") from None
    if matrix.ndim != 2 or matrix.shape[1] != 6:
        raise FieldError(field, f"rows of six numbers, got shape {matrix.shape}")
    return matrix.tolist()


SIMatrix = Annotated[Any, BeforeValidator(_si_matrix)]


# -- the inline finite-element description ---------------------------------------------------
class NodeEntry(SchemaSection):
    id: _NODE
    xyz: Annotated[list[float], _array_in("m", ((3,),))]


class MaterialEntry(BuildableSection):
    """An isotropic material: ``E``, ``density`` and ``G`` or ``nu`` (default 0.3)."""

    E: Annotated[float, in_unit("Pa")]
    density: Annotated[float, in_unit("kg/m**3")]
    nu: Annotated[float | None, in_unit("")] = None
    G: Annotated[float | None, in_unit("Pa")] = None

    def build(self) -> Any:
        from flexsat.structures.sections import Material

        if self.nu is not None and self.G is not None:
            raise FieldError("G", "give G or nu, not both (G = E / (2 (1 + nu)))")
        nu = 0.3 if self.nu is None else self.nu
        try:
            return Material(E=self.E, rho=self.density, nu=nu, G=self.G)
        except FieldError as exc:  # the runtime names its density rho
            raise FieldError("density" if exc.field == "rho" else exc.field, exc.rule) from None


#: the fields each section shape takes (Section's constructors)
SECTION_SHAPES = {
    "general": ("area", "Iy", "Iz", "J"),
    "tube": ("outer_diameter", "thickness"),
    "circle": ("diameter",),
    "rectangle": ("width", "height"),
}


class SectionEntry(BuildableSection):
    """A beam cross-section: ``area``, ``Iy``, ``Iz``, ``J``, or a ``shape`` and its
    dimensions (:data:`SECTION_SHAPES`)."""

    shape: Literal["general", "tube", "circle", "rectangle"] = "general"
    area: Annotated[float | None, in_unit("m**2")] = None
    Iy: Annotated[float | None, in_unit("m**4")] = None
    Iz: Annotated[float | None, in_unit("m**4")] = None
    J: Annotated[float | None, in_unit("m**4")] = None
    outer_diameter: Annotated[float | None, in_unit("m")] = None
    thickness: Annotated[float | None, in_unit("m")] = None
    diameter: Annotated[float | None, in_unit("m")] = None
    width: Annotated[float | None, in_unit("m")] = None
    height: Annotated[float | None, in_unit("m")] = None

    def build(self) -> Any:
        from flexsat.structures.sections import Section

        wanted = SECTION_SHAPES[self.shape]
        for name in self.model_fields_set - {"shape"}:
            if name not in wanted:
                raise FieldError(
                    name,
                    f"not a dimension of a {self.shape} section (it takes {', '.join(wanted)})",
                )
        for name in wanted:
            if getattr(self, name) is None:
                raise FieldError(name, f"required by a {self.shape} section")
        if self.shape == "general":
            return Section.general(self.area, self.Iy, self.Iz, self.J)  # type: ignore[arg-type]
        if self.shape == "tube":
            return Section.tube(self.outer_diameter, self.thickness)  # type: ignore[arg-type]
        if self.shape == "circle":
            return Section.circle(self.diameter)  # type: ignore[arg-type]
        return Section.rectangle(self.width, self.height)  # type: ignore[arg-type]


class ElementEntry(SchemaSection):
    kind: Literal["frame", "rod"] = "frame"
    nodes: Annotated[list[_NODE], Field(min_length=2, max_length=2)]
    material: str
    section: str
    orientation: Direction = None
    offsets: Offsets = None
    lumped: bool = False


class MassEntry(SchemaSection):
    node: _NODE
    mass: Annotated[float, in_unit("kg")]
    inertia: Inertia = None
    offset: Vector = None


class RigidLinkEntry(SchemaSection):
    node: _NODE
    nodes: list[_NODE] = Field(min_length=1, max_length=_MAX_ENTRIES)


class ClampEntry(SchemaSection):
    node: _NODE
    dofs: Literal["all"] | list[Literal["ux", "uy", "uz", "rx", "ry", "rz"]] = "all"


class FESection(BuildableSection):
    """An inline finite-element model (module docstring); checked at load time by building its
    :class:`~flexsat.structures.fem.Structure` (the modal solve waits for the run)."""

    nodes: list[NodeEntry] = Field(min_length=1, max_length=_MAX_ENTRIES)
    materials: dict[str, MaterialEntry] = Field(min_length=1)
    sections: dict[str, SectionEntry] = Field(min_length=1)
    elements: list[ElementEntry] = Field(min_length=1, max_length=_MAX_ENTRIES)
    masses: list[MassEntry] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    rigid_links: list[RigidLinkEntry] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    clamps: list[ClampEntry] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    n_modes: Annotated[int, integer_in(1, limits.MAX_MODES)] = 10
    damping: Damping = 0.0
    reference: Vector = None

    def description(self) -> FEDescription:
        """The SI description (:class:`~flexsat.structures.fe_description.FEDescription`)."""
        from flexsat.structures.fe_description import (
            ClampSpec,
            ElementSpec,
            FEDescription,
            MassSpec,
            NodeSpec,
            RigidLinkSpec,
        )

        return FEDescription(
            nodes=[NodeSpec(n.id, n.xyz) for n in self.nodes],
            materials={k: v.build() for k, v in self.materials.items()},
            sections={k: v.build() for k, v in self.sections.items()},
            elements=[
                ElementSpec(
                    e.kind,
                    (e.nodes[0], e.nodes[1]),
                    e.material,
                    e.section,
                    e.orientation,
                    e.offsets,
                    e.lumped,
                )
                for e in self.elements
            ],
            masses=[MassSpec(m.node, m.mass, m.inertia, m.offset) for m in self.masses],
            rigid_links=[RigidLinkSpec(r.node, tuple(r.nodes)) for r in self.rigid_links],
            clamps=[
                ClampSpec(c.node, c.dofs if isinstance(c.dofs, str) else tuple(c.dofs))
                for c in self.clamps
            ],
            n_modes=self.n_modes,
            damping=self.damping,
            reference=self.reference,
        )

    def build(self) -> Any:
        return self.description().structure()


# -- a hub with appendages ---------------------------------------------------------------------
class HubAppendageSection(BuildableSection):
    """A rigid hub with ``n_appendages`` identical cantilevered beams with tip bodies
    (:class:`~flexsat.dynamics.hub_appendage.HubAppendageParams`)."""

    hub_inertia: Annotated[float, in_unit("kg*m**2")]
    n_appendages: Annotated[int, integer_in(1, 64)]
    hub_radius: Annotated[float, in_unit("m")]
    length: Annotated[float, in_unit("m")]
    EI: Annotated[float, in_unit("N*m**2")]
    rho: Annotated[float, in_unit("kg/m")]
    tip_mass: Annotated[float, in_unit("kg")] = 0.0
    tip_inertia: Annotated[float, in_unit("kg*m**2")] = 0.0
    damping: Damping = 0.0

    def build(self) -> HubAppendageParams:
        from flexsat.dynamics.hub_appendage import HubAppendageParams

        values = self.model_dump()
        damping = values.pop("damping")
        return HubAppendageParams(
            **values, damping=tuple(damping) if isinstance(damping, list) else damping
        )


# -- the section -------------------------------------------------------------------------------
#: keys that only a file takes
_FILE_KEYS = ("op4", "superelement", "units", "damping", "reference", "rigid_mass", "participation")


class ModelSection(SchemaSection):
    """``model:``: one of ``file``, ``fe``, ``hub_appendage`` (module docstring)."""

    file: str | None = None
    op4: str | None = None
    superelement: Annotated[int | None, integer_in(0, 2**31 - 1, optional=True)] = None
    units: dict[Literal["length", "mass", "time"], str] | None = None
    damping: Damping = None
    reference: Vector = None
    rigid_mass: SIMatrix = None
    participation: SIMatrix = None
    fe: FESection | None = None
    hub_appendage: HubAppendageSection | None = None

    @model_validator(mode="after")
    def _one_source(self) -> Self:
        return self.check_source()

    def check_source(self) -> Self:
        """Exactly one source, and only the options that apply to it (the section's rule)."""
        given = [k for k in ("file", "fe", "hub_appendage") if getattr(self, k) is not None]
        if len(given) != 1:
            raise FieldError(
                "model",
                "give exactly one of file (a modal model on disk), fe (a finite-element "
                "description) or hub_appendage (a hub with appendages)"
                + (f"; got {', '.join(given)}" if given else ""),
            )
        if self.file is None:
            for key in _FILE_KEYS:
                if getattr(self, key) is not None:
                    raise FieldError(key, f"applies to a model file only (model.{given[0]} given)")
            return self
        suffix = Path(self.file).suffix.lower()
        if suffix not in FILE_KINDS:
            raise FieldError(
                "file",
                f"a model file ends in {', '.join(FILE_KINDS)} (netCDF modal model, NASTRAN "
                f"OP2, universal file), got {self.file!r}",
            )
        nastran_only = ("op4", "superelement", "units")
        if FILE_KINDS[suffix] != "nastran":
            for key in nastran_only:
                if getattr(self, key) is not None:
                    raise FieldError(key, "applies to a NASTRAN OP2 file only")
        if FILE_KINDS[suffix] == "netcdf":
            for key in ("rigid_mass", "participation"):
                if getattr(self, key) is not None:
                    raise FieldError(key, "a netCDF modal model carries its own")
        elif FILE_KINDS[suffix] == "uff" and (self.rigid_mass is None) != (
            self.participation is None
        ):
            raise FieldError("participation", "give rigid_mass and participation together")
        if self.units is not None and set(self.units) != {"length", "mass", "time"}:
            raise FieldError("units", "give the model's length, mass and time units")
        if FILE_KINDS[suffix] == "netcdf":
            for key in ("damping", "reference"):
                if getattr(self, key) is not None:
                    raise FieldError(key, "a netCDF modal model carries its own")
        return self

    def modal_model(self, folder: Path) -> ModalModel:
        """The modal model of a ``file`` or ``fe`` section (a file's path relative to
        ``folder``), built once per content in this process
        (:data:`flexsat.scenarios.modal_cache.MODAL_MODELS`: keyed by the section's canonical
        JSON and the digests of the files it reads).

        Raises
        ------
        FieldError
            Located in the section: ``file: no such file ...``, ``fe.elements[3].nodes: ...``,
            a reader's refusal under ``file``.
        """
        from flexsat.scenarios.modal_cache import MODAL_MODELS, section_key

        content = self.model_dump(mode="json")
        if self.fe is not None:
            return MODAL_MODELS.get(section_key(content), self._solve_fe)
        assert self.file is not None  # the section holds exactly one source
        path = _existing(self.file, folder, "file")
        op4 = None if self.op4 is None else _existing(self.op4, folder, "op4")
        # without op4:, the NASTRAN reader takes the OP2's sibling .op4 when there is one
        sibling = path.with_suffix(".op4")
        read = [path, *([op4] if op4 is not None else [sibling] if sibling.is_file() else [])]
        return MODAL_MODELS.get(section_key(content, read), lambda: self._read_file(path, op4))

    def _solve_fe(self) -> ModalModel:
        """The inline FE model's modal solve."""
        assert self.fe is not None
        try:
            return self.fe.description().modal_model()
        except FieldError as exc:
            raise FieldError(f"fe.{exc.field}", exc.rule) from None

    def _read_file(self, path: Path, op4: Path | None) -> ModalModel:
        """The modal model in the file at ``path`` (its reader by suffix)."""
        kind = FILE_KINDS[path.suffix.lower()]
        try:
            if kind == "netcdf":
                from flexsat.structures.modal_model import ModalModel

                return ModalModel.load(path)
            if kind == "uff":
                return self._read_uff(path)
            return self._read_nastran(path, op4)
        except FieldError as exc:
            raise FieldError(f"file.{exc.field}", exc.rule) from None
        except (ValueError, OSError, KeyError, ImportError) as exc:
            raise FieldError(
                "file", f"cannot read {path.name} as a {kind} modal model: {exc}"
            ) from None

    def _options(self) -> dict[str, Any]:
        """The reader options given (SI)."""
        names = ("damping", "reference", "rigid_mass", "participation")
        return {k: getattr(self, k) for k in names if getattr(self, k) is not None}

    def _read_uff(self, path: Path) -> ModalModel:
        from flexsat.structures.io_uff import modal_model_from_uff

        return modal_model_from_uff(path, **self._options())

    def _read_nastran(self, path: Path, op4: Path | None) -> ModalModel:
        """NASTRAN: a NAS2CAM OP2/OP4 pair, or a plain SOL 103 OP2; lengths and mass
        properties given here in SI go to the readers in the model's units
        (:mod:`flexsat.structures.modal_import`: s = √m_u (1, 1, 1, ℓ_u, ℓ_u, ℓ_u))."""
        from flexsat.structures.io_nastran import read_nastran_modes
        from flexsat.structures.io_op2 import read_op2_modes
        from flexsat.structures.modal_import import unit_scales

        units = None if self.units is None else {str(k): v for k, v in self.units.items()}
        length, mass, _ = unit_scales(units)
        s = np.sqrt(mass) * np.array([1.0, 1.0, 1.0, length, length, length])
        options = self._options()
        if "reference" in options:
            options["reference"] = np.asarray(options["reference"]) / length
        if "rigid_mass" not in options and "participation" not in options:
            return read_nastran_modes(
                path, op4, superelement=self.superelement or 0, units=units, **options
            )
        if op4 is not None or path.with_suffix(".op4").is_file():
            raise FieldError(
                "participation", "applies to a plain SOL 103 OP2 (an OP4 carries the mass)"
            )
        if "rigid_mass" in options:
            options["rigid_mass"] = np.asarray(options["rigid_mass"]) / np.outer(s, s)
        if "participation" in options:
            options["participation"] = np.asarray(options["participation"]) / s
        return read_op2_modes(path, units=units, **options)


def _existing(name: str, folder: Path, field: str) -> Path:
    path = Path(name)
    path = path if path.is_absolute() else folder / path
    if not path.is_file():
        raise FieldError(field, f"no such file: {path}")
    return path


def model_label(section: ModelSection) -> str:
    """What the report names instead of a case: the file, or the kind of inline model."""
    if section.file is not None:
        return f"model file {section.file}"
    if section.fe is not None:
        return "inline finite-element model"
    return "hub with appendages"


# -- the plant ---------------------------------------------------------------------------------
_AXIS = Literal["x", "y", "z", "X", "Y", "Z"]
_POINT = tuple[_NODE, _AXIS]


class ActuatorEntry(SchemaSection):
    """An input of a constrained structure (:class:`~flexsat.dynamics.structural.Actuator`):
    ``node`` (a force or torque) or ``nodes`` (a moment pair), ``axis``."""

    name: str
    kind: Literal["force", "torque", "moment_pair"] = "force"
    node: _NODE | None = None
    nodes: Annotated[list[_NODE] | None, Field(min_length=2, max_length=2)] = None
    axis: _AXIS
    gain: Annotated[float, in_unit("")] = 1.0


class SensorEntry(SchemaSection):
    """An output of a constrained structure (:class:`~flexsat.dynamics.structural.Sensor`)."""

    name: str
    kind: Literal["displacement", "rotation", "strain"] = "displacement"
    node: _NODE | None = None
    nodes: Annotated[list[_NODE] | None, Field(min_length=2, max_length=2)] = None
    axis: _AXIS
    rate: bool = False
    gain: Annotated[float, in_unit("")] = 1.0


#: which plant option applies to which model
_PLANT_OPTIONS = {
    "spacecraft": (
        "rigid",
        "n_modes",
        "torque_node",
        "forces",
        "displacements",
        "rotations",
        "translation",
    ),
    "structure": ("n_modes", "actuators", "sensors"),
    "hub_appendage": ("n_modes", "stiffening"),
}


class ModelPlantOptions(SchemaSection):
    """``plant:`` of a scenario with a ``model:`` (module docstring); which options apply
    depends on the model (:data:`_PLANT_OPTIONS`), checked when the plant is built."""

    n_modes: Annotated[int | None, integer_in(1, limits.MAX_MODES, optional=True)] = None
    torque_node: _NODE | None = None
    forces: list[_POINT] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    displacements: list[_POINT] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    rotations: list[_POINT] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    translation: bool = False
    rigid: bool = False
    actuators: list[ActuatorEntry] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    sensors: list[SensorEntry] = Field(default_factory=list, max_length=_MAX_ENTRIES)
    stiffening: bool = False


def model_plant(section: ModelSection, options: ModelPlantOptions, folder: Path) -> Plant:
    """The plant of a ``model:`` section under its ``plant:`` options (module docstring).

    Raises
    ------
    FieldError
        ``model.<field>: rule`` for a model that cannot be read or built, ``plant.<option>:
        rule`` for an option the plant refuses or that does not apply to this model.
    """
    hub = section.hub_appendage
    if hub is not None:
        _only(options, "hub_appendage", "a hub with appendages")
        try:
            return _located("plant", lambda: _hub_appendage(hub, options))
        except FieldError as exc:  # damping ratios that do not match the modes: the model's
            if exc.field == "plant.damping":
                raise FieldError("model.hub_appendage.damping", exc.rule) from None
            raise
    modal = _located("model", lambda: section.modal_model(folder))
    if modal.boundary == "free":
        _only(options, "spacecraft", "a free-free model (a three-axis spacecraft)")
        return _located("plant", lambda: _spacecraft(modal, options))
    _only(options, "structure", f"a {modal.boundary} model (a structure)")
    return _located("plant", lambda: _structure(modal, options))


def _located(path: str, build: Any) -> Any:
    try:
        return build()
    except FieldError as exc:
        field = exc.field if exc.field.startswith(path + ".") else f"{path}.{exc.field}"
        raise FieldError(field, exc.rule) from None
    except ValueError as exc:  # a runtime refusal that names no field: placed at the section
        raise FieldError(path, str(exc)) from None


def _only(options: ModelPlantOptions, plant: str, what: str) -> None:
    for name in options.model_fields_set:
        if name not in _PLANT_OPTIONS[plant]:
            raise FieldError(
                f"plant.{name}",
                f"does not apply to {what}; its options: {', '.join(_PLANT_OPTIONS[plant])}",
            )


def _axis(axis: str) -> str:
    return axis.lower()


def _spacecraft(modal: ModalModel, options: ModelPlantOptions) -> Plant:
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft

    if options.rigid:  # the same body without its modes: the inertia about its centre of mass
        from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft

        extra = sorted(options.model_fields_set - {"rigid"})
        if extra:
            raise FieldError(extra[0], "a rigid spacecraft has no modes, nodes or forces")
        return RigidSpacecraft(modal.inertia())
    return FlexibleSpacecraft(
        modal,
        forces=[(n, _axis(a)) for n, a in options.forces],
        displacements=[(n, _axis(a)) for n, a in options.displacements],
        rotations=[(n, _axis(a)) for n, a in options.rotations],
        torque_node=options.torque_node,
        translation=options.translation,
        n_modes=options.n_modes,
    )


def _structure(modal: ModalModel, options: ModelPlantOptions) -> Plant:
    from flexsat.dynamics.structural import Actuator, Sensor, StructuralPlant

    if options.n_modes is not None:
        if options.n_modes > modal.n_modes:
            raise FieldError(
                "n_modes", f"at most the model's {modal.n_modes} modes, got {options.n_modes}"
            )
        modal = modal.truncate(options.n_modes)
    if not options.actuators and not options.sensors:
        raise FieldError("actuators", "a structure needs at least one actuator or sensor")

    def at(entry: ActuatorEntry | SensorEntry, path: str) -> object:
        if entry.kind in ("moment_pair", "strain"):
            if entry.nodes is None or entry.node is not None:
                raise FieldError(path, f"a {entry.kind} takes nodes: [a, b] only")
            return (entry.nodes[0], entry.nodes[1])
        if entry.node is None or entry.nodes is not None:
            raise FieldError(path, f"a {entry.kind} takes node only")
        return entry.node

    inputs = [
        Actuator(a.name, a.kind, at(a, f"actuators[{i}]"), _axis(a.axis), a.gain)
        for i, a in enumerate(options.actuators)
    ]
    outputs = [
        Sensor(s.name, s.kind, at(s, f"sensors[{i}]"), _axis(s.axis), s.gain, s.rate)
        for i, s in enumerate(options.sensors)
    ]
    return StructuralPlant.from_modal_model(modal, inputs, outputs)


def _hub_appendage(section: HubAppendageSection, options: ModelPlantOptions) -> Plant:
    from flexsat.dynamics.hub_appendage import HubAppendage

    params = section.build()
    extra: dict[str, Any] = {} if options.n_modes is None else {"n_modes": options.n_modes}
    return HubAppendage(params, stiffening=options.stiffening, **extra)
