r"""The TAMU 5′ × 5′ monolithic aluminium grid (Texas A&M, 1987–1989), hanging in a vertical plane.

Sources (Att. 4, 6 and 8 of Junkins, Pollock & Rahman 1990, the Texas A&M final report, AFOSR
F49620-87-C-0078):

* Att. 4 (Kim & Junkins), Table 1 "Material Properties of Grid Model": EI, GJ,
  ρA, ρJ, printed in lb-in-s units with an SI column; Fig. 1 caption: "first natural
  frequency is .8 Hz, 10 modes have natural frequencies below 30 Hz"; output y_d is the normal
  displacement of the lower-left corner.
* Att. 6 (James & Junkins, AAS 89-425): 25 structure nodes, nodes 21–25 fixed,
  36 Paz grid elements, 60 dof; node i+5 directly above node i; three Clifton Precision
  AS-780D-100 motors with brass reaction wheels at nodes 3, 7 and 9 (masses not given); gravity
  stiffening by a pendulum model; Table 1: modelled .809, 2.21, 4.48, 5.65,
  7.76 Hz and experiment .877, 2.19, 4.81, 6.17, 8.18 Hz; Table 2: modelled and
  measured mode-1 shape, mass normalised with the analytical mass matrix.
* Att. 8 (Junkins & James, AAS 88-015), §4.0: "5′ × 5′ grid, with 12.5″ × 2″ × 1/8″ members",
  3003-H14; Figure 4 table: modelled .90, 2.34, 4.85, 6.05, 7.78, 12.84 Hz (the
  FE model of Das et al., ref. 8), measured .91, 2.07, 4.76, 5.14, 6.57, 10.86 Hz.

Model (interpretation choices, all documented in docs/structures_benchmarks.md)
----------------------------------------------------------------------------
* Plane X-Y is the grid plane, **Y points up**, Z is the out-of-plane normal; gravity acts
  along −Y.  Paper node k is our node id k: node k sits at column (k − 1) mod 5 and row
  (k − 1) // 5, i.e. x = s ((k − 1) mod 5), y = s ((k − 1) // 5).  Node 1 (x = y = 0) is the
  lower-left corner (output y_d of Att. 4) if the paper numbers from the left as seen in its
  Fig. 1, which the OCR does not show; node 5 is its mirror image, with identical modal
  amplitudes.  Node 3 (motor, Att. 6) is the bottom-centre node; nodes 7 and 9 the second row,
  one bay either side of the centre column.  Nodes 21–25 (top row) are clamped.
* Members: 16 horizontal (rows 1–4) + 20 vertical (4 storeys × 5 columns) = 36 grid elements
  (``Structure.add_grid``, dofs uz, rx, ry).  The 4 members between the clamped top-row nodes
  carry no dof and are not modelled, which is how 25 nodes give 36 elements and 20 × 3 = 60 dof.
* Node spacing ``s`` = **14.5 in** (default), the centre-line pitch of 2″-wide members with
  12.5″ clear length: 5 × 2″ + 4 × 12.5″ = 60″ = 5′ (Att. 8, §4.0).  The 15 in of a naive
  60″ / 4 bays is available as an override (``spacing="15 in"``).
* Gravity stiffening: the grid element has no axial dof (``gravity_preload`` gives grid members
  no force), so the tension of each vertical member is found by statics, as in the paper's
  pendulum model (Att. 6 Eq. 14, "pendulums connected only in the vertical direction"): each node
  carries half the mass of every member it touches plus its motor; a vertical member carries
  the weight of the nodes of its column at or below its lower end.  The tension enters through
  the consistent geometric stiffness of the member (``set_axial_preload``;
  ``gravity_model="consistent"``, default) or, as in the paper, as a string stiffness T/L on the
  z displacements only (``gravity_model="string"``: massless pre-tensioned rods in parallel with
  the vertical members); the two differ by 0.4 % on mode 1.
* Motors: masses never published.  ``motor_mass`` (default **0 kg: no motors**) and optional
  ``motor_inertia`` (about both in-plane axes) are placed at ``motor_nodes`` (default 3, 7, 9).
  A motor mass also adds to the member tensions.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.input_checks import FieldError, require_count
from flexsat.structures.fem import Structure
from flexsat.structures.sections import Material
from flexsat.units import Q_, to_si

if TYPE_CHECKING:
    from flexsat.dynamics.structural import StructuralPlant
    from flexsat.structures.modal_model import ModalModel

SOURCE = CASES["tamu_grid"].source

#: Published values, exactly as printed ("lb" of the paper is pound-force: lbf in pint)
PUBLISHED: dict[str, Any] = {
    # Att. 4 Table 1, US column as used; the SI column as printed
    "EI": "3255.2 lbf*in**2",
    "GJ": "4943.0 lbf*in**2",
    "rho_A": "0.0000648 lbf*s**2/in**2",  # printed "lb·sec²·in²" [OCR]; mass per length
    "rho_J": "0.0000217 lbf*s**2",
    "EI_si_printed": "9.34982 N*m**2",  # = 3258.0 lb in²; 3255.2 lb in² is 9.34182 (one digit)
    "GJ_si_printed": "14.18550 N*m**2",
    "rho_A_si_printed": "0.44678 kg/m",
    "rho_J_si_printed": "0.0000965 kg*m",
    # geometry: Att. 4 caption, Att. 6 "Hardware Description" and "Initial Model", Att. 8 §4.0
    "size": "5 ft",
    "member_clear_length": "12.5 in",
    "member_width": "2 in",
    "member_thickness": "0.125 in",
    "nodes": 25,
    "elements": 36,
    "dof": 60,
    # Att. 4 Fig. 1 caption
    "first_frequency": "0.8 Hz",
    "modes_below_30_hz": 10,
    # Att. 8 Figure 4 table, Hz
    "att8_modelled_hz": (0.90, 2.34, 4.85, 6.05, 7.78, 12.84),
    "att8_measured_hz": (0.91, 2.07, 4.76, 5.14, 6.57, 10.86),
    "att8_identified_hz": (0.92, 2.06, 4.76, 5.58, 7.09, 11.57),
    # Att. 6 Table 1, Hz (model with motors and gravity correction)
    "att6_modelled_hz": (0.809, 2.21, 4.48, 5.65, 7.76),
    "att6_experiment_hz": (0.877, 2.19, 4.81, 6.17, 8.18),
    "att6_damping_ratio": (0.00603, 0.00489, 0.01105, 0.00596, 0.01293),
    # Att. 6 Table 2: mode-1 z amplitude at nodes 1-20, mass-normalised (US units)
    "att6_mode1_modelled": (
        8.25,
        8.35,
        8.40,
        8.35,
        8.25,
        5.44,
        5.52,
        5.55,
        5.52,
        5.44,
        2.85,
        2.90,
        2.92,
        2.90,
        2.85,
        0.871,
        0.897,
        0.906,
        0.897,
        0.871,
    ),
    "att6_mode1_experiment": (
        7.66,
        7.83,
        8.18,
        7.97,
        8.54,
        4.99,
        5.10,
        4.94,
        6.17,
        6.23,
        2.12,
        2.78,
        3.57,
        3.33,
        3.95,
        1.14,
        0.763,
        1.26,
        1.59,
        1.43,
    ),
    # Att. 10 Table 1, a second measurement campaign, Hz
    "att10_measured_hz": (0.92, 2.32, 4.93, 6.38, 7.27),
}

N_SIDE = 5
#: "consistent": geometric stiffness of the grid members (default); "string": Att. 6 Eq. 14
GRAVITY_MODELS = ("consistent", "string")
CLAMPED_NODES = tuple(range(21, 26))
LOWER_LEFT_NODE = 1  #: the paper's "lower-left corner" (output y_d of Att. 4), see module doc
#: Stiffness substructures for identification (Att. 6 Eq. 5 scalings γ_k): the vertical members
#: into the clamped row carry the clamp's compliance, the least certain part of the a-priori model
SUBSTRUCTURES = ("clamp verticals", "verticals", "horizontals")
#: (lbf s²/in)^(-1/2) per kg^(-1/2): mass-normalised shapes in the units of Att. 6 Table 2
_SHAPE_TO_US = float(np.sqrt(Q_(1, "lbf*s**2/in").to("kg").magnitude))


def _nodes(raw: Any, name: str) -> tuple[int, ...]:
    """Node ids 1..20 (not the clamped top row), from a sequence or "3,7,9"."""
    items: list[Any]
    if isinstance(raw, str):
        items = [p for p in raw.replace(";", ",").split(",") if p.strip()]
    elif isinstance(raw, (int, np.integer)) and not isinstance(raw, bool):
        items = [raw]
    else:
        try:
            items = list(raw)
        except TypeError:
            raise FieldError(name, f"must be node ids in 1..20, got {raw!r}") from None
    out = []
    for item in items:
        try:
            n = require_count(item.strip() if isinstance(item, str) else item, name)
        except ValueError:
            try:
                n = require_count(float(item), name)
            except (TypeError, ValueError):
                raise FieldError(name, f"must be node ids in 1..20, got {raw!r}") from None
        if not 1 <= n <= 20:
            raise FieldError(name, f"must be node ids in 1..20 (21-25 are clamped), got {n}")
        out.append(n)
    if len(set(out)) != len(out):
        raise FieldError(name, f"node ids must be distinct, got {raw!r}")
    return tuple(out)


#: the overridable inputs of the case, defaults as written
_INPUTS = {
    "EI": Param(PUBLISHED["EI"], "N*m**2"),
    "GJ": Param(PUBLISHED["GJ"], "N*m**2"),
    "rho_A": Param(PUBLISHED["rho_A"], "kg/m"),
    "rho_J": Param(PUBLISHED["rho_J"], "kg*m", "nonneg"),
    "spacing": Param("14.5 in", "m"),
    "g": Param("9.80665 m/s**2", "m/s**2", "nonneg"),
    "gravity": Param(True, rule="flag"),
    "gravity_model": Param("consistent", rule="choice", choices=GRAVITY_MODELS),
    "motor_mass": Param("0 kg", "kg", "nonneg"),
    "motor_inertia": Param("0 kg*m**2", "kg*m**2", "nonneg"),
    "motor_nodes": Param((3, 7, 9), rule=_nodes),
}


@dataclass(frozen=True)
class TamuGridCase:
    """The TAMU grid (SI); see the module docstring for geometry, numbering and gravity."""

    EI: float
    GJ: float
    rho_A: float
    rho_J: float
    spacing: float
    g: float
    gravity: bool
    gravity_model: str
    motor_mass: float
    motor_inertia: float
    motor_nodes: tuple
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # -- geometry -------------------------------------------------------------------------------
    @staticmethod
    def node_position(node: int) -> tuple[int, int]:
        """(column, row) of paper node ``node`` (1..25), both from 0 at the lower left."""
        return (node - 1) % N_SIDE, (node - 1) // N_SIDE

    @property
    def members(self) -> list[tuple[int, int]]:
        """The 36 members (n1, n2): 16 horizontal (rows 1-4), then 20 vertical (lower, upper)."""
        horizontal = [
            (5 * r + c + 1, 5 * r + c + 2) for r in range(N_SIDE - 1) for c in range(N_SIDE - 1)
        ]
        vertical = [
            (5 * r + c + 1, 5 * r + c + 6) for r in range(N_SIDE - 1) for c in range(N_SIDE)
        ]
        return horizontal + vertical

    @property
    def substructures(self) -> tuple[str, ...]:
        """Names of the stiffness substructures (:data:`SUBSTRUCTURES`)."""
        return SUBSTRUCTURES

    @staticmethod
    def substructure_of(member: tuple[int, int]) -> str:
        """The :data:`SUBSTRUCTURES` group of ``member`` (n1, n2)."""
        a, b = member
        if b - a != N_SIDE:
            return "horizontals"
        return "clamp verticals" if b in CLAMPED_NODES else "verticals"

    def lumped_masses(self) -> dict[int, float]:
        """Mass carried by each node (kg): half of every member it touches, plus its motor."""
        m = {n: 0.0 for n in range(1, 26)}
        for a, b in self.members:
            m[a] += self.rho_A * self.spacing / 2
            m[b] += self.rho_A * self.spacing / 2
        for n in self.motor_nodes:
            m[n] += self.motor_mass
        return m

    def member_tensions(self) -> dict[tuple[int, int], float]:
        """Gravity tension (N) of each vertical member: the weight of its column's nodes at or
        below its lower end (pendulum-chain statics, Att. 6 Eq. 14)."""
        m = self.lumped_masses()
        out = {}
        for lower, upper in self.members[16:]:
            column = [n for n in range(lower, 0, -N_SIDE)]
            out[(lower, upper)] = self.g * sum(m[n] for n in column)
        return out

    @property
    def total_mass(self) -> float:
        """Moving mass (kg): the 36 members and the motors (the clamped tab excluded)."""
        return 36 * self.rho_A * self.spacing + len(self.motor_nodes) * self.motor_mass

    def structure(
        self, gravity: bool | None = None, stiffness_scale: Mapping[str, float] | None = None
    ) -> Structure:
        """The 25-node, 36-member grid; ``gravity`` (default: the case's flag) sets the
        vertical members' tensions; ``stiffness_scale`` maps :data:`SUBSTRUCTURES` names to
        factors on the members' EI and GJ (default 1)."""
        gravity = self.gravity if gravity is None else bool(gravity)
        scale = dict(stiffness_scale or {})
        for name, factor in scale.items():
            if name not in SUBSTRUCTURES:
                raise FieldError(
                    "stiffness_scale",
                    f"unknown substructure {name!r}; known: {', '.join(SUBSTRUCTURES)}",
                )
            if not (np.isfinite(factor) and factor > 0):
                raise FieldError(
                    "stiffness_scale", f"{name!r} must be a finite factor > 0, got {factor!r}"
                )
        s = Structure("TAMU 5 ft x 5 ft grid")
        for n in range(1, 26):
            c, r = self.node_position(n)
            s.add_node(n, (c * self.spacing, r * self.spacing, 0.0))
        ids = {}
        for a, b in self.members:
            kind = "vertical" if b - a == N_SIDE else "horizontal"
            k = scale.get(self.substructure_of((a, b)), 1.0)
            ids[(a, b)] = s.add_grid(
                a, b, k * self.EI, k * self.GJ, self.rho_A, self.rho_J, label=f"{kind} {a}-{b}"
            )
        if self.motor_mass > 0 or self.motor_inertia > 0:
            for n in self.motor_nodes:
                s.add_mass(
                    n,
                    self.motor_mass,
                    inertia=(self.motor_inertia, self.motor_inertia, 0.0)
                    if self.motor_inertia > 0
                    else None,
                )
                # a lumped mass touches ux, uy (and rz with an inertia); the grid has no
                # stiffness there: the motor moves with the plate (uz, rx, ry) only
                s.clamp(n, ("ux", "uy", "rz") if self.motor_inertia > 0 else ("ux", "uy"))
        for n in CLAMPED_NODES:
            s.clamp(n)
        if gravity and self.g > 0:
            tensions = self.member_tensions()
            if self.gravity_model == "consistent":
                for member, tension in tensions.items():
                    s.set_axial_preload(ids[member], tension)
            else:  # Att. 6 Eq. 14: string stiffness T/L on uz only, by massless pre-tensioned rods
                string = Material(E=1.0, rho=0.0, name="massless string")
                for (a, b), tension in tensions.items():
                    s.set_axial_preload(
                        s.add_rod(a, b, string, 1.0, label=f"string {a}-{b}"), tension
                    )
                for n in range(1, 21):
                    s.clamp(n, ("ux", "uy"))  # the rods' in-plane dofs: not part of the model
        return s

    def _modes(self, gravity: bool):
        key = ("modes", bool(gravity))
        if key not in self._cache:
            asm = self.structure(gravity).assemble()
            self._cache[key] = asm.modes(asm.n_dofs)
        return self._cache[key]

    @property
    def n_dofs(self) -> int:
        return self._modes(self.gravity).assembly.n_dofs

    # -- case protocol --------------------------------------------------------------------------
    def frequencies_hz(self, n_modes: int, gravity: bool | None = None) -> np.ndarray:
        """First ``n_modes`` natural frequencies, Hz (with gravity stiffening unless the case
        or ``gravity`` says otherwise)."""
        n = require_count(n_modes, "n_modes")
        f = self._modes(self.gravity if gravity is None else gravity).frequencies_hz
        if n > len(f):
            raise FieldError("n_modes", f"the grid has {len(f)} modes, got {n}")
        return f[:n].copy()

    def mode_descriptions(self, n_modes: int) -> list[str]:
        """Symmetric or antisymmetric about the centre column, and the bottom-edge shape."""
        n = require_count(n_modes, "n_modes")
        modes = self._modes(self.gravity)
        if n > modes.shapes.shape[1]:
            raise FieldError("n_modes", f"the grid has {modes.shapes.shape[1]} modes, got {n}")
        uz = modes.at_nodes()[:n, :20, 2].reshape(n, 4, 5)  # rows 1-4 (bottom first), columns
        out = []
        for w in uz:
            mirrored = w[:, ::-1]
            sym = np.abs(w + mirrored).max() >= np.abs(w - mirrored).max()
            # height profile: row sums (symmetric) or left-minus-right (antisymmetric)
            profile = w.sum(axis=1) if sym else (w[:, :2] - w[:, 3:]).sum(axis=1)
            profile = np.append(profile, 0.0)[::-1]  # from the clamp (0) down to the free edge
            big = profile[np.abs(profile) > 1e-3 * np.abs(profile).max()]
            crossings = int(np.sum(np.sign(big[1:]) != np.sign(big[:-1])))
            row = w[np.argmax(np.abs(w).max(axis=1))]  # the row that moves most
            row = row[np.abs(row) > 1e-3 * np.abs(row).max()]
            across = int(np.sum(np.sign(row[1:]) != np.sign(row[:-1])))
            kind = "bending" if sym else "torsion"
            out.append(
                f"{kind} ({'symmetric' if sym else 'antisymmetric'} about the centre "
                f"column): {crossings} node line(s) across the height, {across} along "
                "the rows"
            )
        return out

    def mode1_shape_us(self, gravity: bool | None = None) -> np.ndarray:
        """Mode-1 z amplitude at nodes 1..20, mass normalised, in (lbf s²/in)^(-1/2) as Att. 6
        Table 2 (sign: positive at node 3)."""
        modes = self._modes(self.gravity if gravity is None else gravity)
        w = modes.at_nodes()[0, :20, 2] * _SHAPE_TO_US
        return w * np.sign(w[2])

    def mode_details(self, n_modes: int) -> dict:
        """Published vs computed frequencies (with and without gravity), Hz; JSON-ready."""
        n = require_count(n_modes, "n_modes")
        f_g = self.frequencies_hz(max(n, 6), gravity=True)
        f_0 = self.frequencies_hz(max(n, 6), gravity=False)
        att8 = np.array(PUBLISHED["att8_modelled_hz"])
        att6 = np.array(PUBLISHED["att6_modelled_hz"])
        all_g = self._modes(True).frequencies_hz
        all_0 = self._modes(False).frequencies_hz
        return {
            "with_gravity_hz": f_g[:n].tolist(),
            "without_gravity_hz": f_0[:n].tolist(),
            "att8_modelled_hz": att8.tolist(),
            "att8_measured_hz": list(PUBLISHED["att8_measured_hz"]),
            "rel_error_vs_att8_with_gravity": (f_g[:6] / att8 - 1).tolist(),
            "rel_error_vs_att8_without_gravity": (f_0[:6] / att8 - 1).tolist(),
            "att6_modelled_hz": att6.tolist(),
            "att6_experiment_hz": list(PUBLISHED["att6_experiment_hz"]),
            "rel_error_vs_att6_with_gravity": (f_g[:5] / att6 - 1).tolist(),
            "published_first_frequency_hz": to_si(PUBLISHED["first_frequency"], "Hz"),
            "published_modes_below_30_hz": PUBLISHED["modes_below_30_hz"],
            "modes_below_30_hz_with_gravity": int(np.sum(all_g < 30.0)),
            "modes_below_30_hz_without_gravity": int(np.sum(all_0 < 30.0)),
            "mode1_shape_us": self.mode1_shape_us(True).tolist(),
            "att6_mode1_modelled_us": list(PUBLISHED["att6_mode1_modelled"]),
            "vertical_member_tension_n": [t for t in self.member_tensions().values()],
            "total_mass_kg": self.total_mass,
            "motors": {
                "mass_kg": self.motor_mass,
                "inertia_kg_m2": self.motor_inertia,
                "nodes": list(self.motor_nodes),
            },
        }

    def plant(
        self,
        n_modes: int = 10,
        damping: float = 0.01,
        force_node: int = 1,
        sensor_nodes: Sequence[int] = (1, 3),
    ) -> StructuralPlant:
        """The hanging grid as a plant: an out-of-plane (z) force ``force`` at ``force_node``
        (a shaker; default the free lower-left corner, which drives bending and torsion), the
        displacements ``displacement_<node>`` (m) and rates at ``sensor_nodes`` (default the
        corner and the middle of the free bottom edge; paper nodes 1-25 from the lower left,
        the top row 21-25 clamped), on its first ``n_modes`` modes (gravity as the case sets
        it) with ``damping`` on each (:mod:`flexsat.cases.structure_plants`)."""
        return _grid_plant(self, n_modes, damping, force_node, sensor_nodes)

    def modal_model(
        self, n_modes: int, damping: npt.ArrayLike = 0.0, gravity: bool | None = None
    ) -> ModalModel:
        """:class:`~flexsat.structures.modal_model.ModalModel` of the first ``n_modes`` modes,
        cantilevered at the centre of the clamped top row (x = 2 s, y = 4 s)."""
        from flexsat.structures.fem import FEModes
        from flexsat.structures.modal_model import ModalModel

        n = require_count(n_modes, "n_modes")
        modes = self._modes(self.gravity if gravity is None else gravity)
        if n > modes.shapes.shape[1]:
            raise FieldError("n_modes", f"the grid has {modes.shapes.shape[1]} modes, got {n}")
        cut = FEModes(modes.omegas[:n], modes.shapes[:, :n], modes.assembly)
        return ModalModel.from_fe(
            cut,
            damping=damping,
            reference=(2 * self.spacing, 4 * self.spacing, 0.0),
            boundary="cantilevered",
        )


def _grid_plant(
    case: TamuGridCase, n_modes: int, damping: float, force_node: int, sensor_nodes: Sequence[int]
) -> StructuralPlant:
    from flexsat.cases.structure_plants import point_force_plant
    from flexsat.structures.fem import FEModes

    n = require_count(n_modes, "n_modes")
    modes = case._modes(case.gravity)
    if n > modes.shapes.shape[1]:
        raise FieldError("n_modes", f"the grid has {modes.shapes.shape[1]} modes, got {n}")
    cut = FEModes(modes.omegas[:n], modes.shapes[:, :n], modes.assembly)
    return point_force_plant(
        cut, force_node, sensor_nodes, "z", damping, (2 * case.spacing, 4 * case.spacing, 0.0)
    )


def tamu_grid(**overrides: Any) -> TamuGridCase:
    """Build the TAMU grid; override any input by name, as a number (SI) or a unit string.

    Inputs: ``EI``, ``GJ`` (N m²), ``rho_A`` (kg/m), ``rho_J`` (kg m), ``spacing`` (m, default
    14.5 in), ``g`` (m/s²), ``gravity`` (bool, default True), ``gravity_model`` ("consistent"
    or "string"), ``motor_mass`` (kg, default 0:
    no motors), ``motor_inertia`` (kg m², about the in-plane axes), ``motor_nodes`` (default
    3, 7, 9).

    >>> case = tamu_grid(motor_mass="0.5 kg", spacing="15 in")  # doctest: +SKIP
    """
    return TamuGridCase(**read_inputs("tamu_grid", _INPUTS, overrides))


__all__ = [
    "CLAMPED_NODES",
    "GRAVITY_MODELS",
    "LOWER_LEFT_NODE",
    "PUBLISHED",
    "SOURCE",
    "SUBSTRUCTURES",
    "TamuGridCase",
    "tamu_grid",
]
