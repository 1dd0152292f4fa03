"""Agrawal & Bang two-beam L structure with three collocated piezoelectric pairs.

B. N. Agrawal and H. Bang, *Adaptive Structures for Large Precision Antennas*, Acta Astronautica
1996 (IAF-94.1.4.202), §4: "two elastic
structures connected in orthogonal configuration" (§4), three collocated piezoceramic
sensor/actuator pairs, actuator 1 "at the root of the first structure" (§4), the actuator a
bending moment M_a = a_1 V (Eq. 36) and the sensor a voltage proportional to the local bending
(Eq. 37), three flexible modes retained (§4). Figs. 1–2 (geometry, patch positions) are lost
and the experiment's reference [9] is missing: no dimension, property, frequency or gain a_1, a_2
of the structure is published.

Model used here (every value a parameter, documented in docs/agrawal_bang.md):

- planar Euler–Bernoulli beams (beam2d, axial + in-plane bending) of aluminium strip
  (6061-T6: E = 68.9 GPa, ρ = 2700 kg/m³), 2 in × 1/8 in, bending across the 1/8 in thickness;
- structure 1 of length l_1 along +y (n̂_2) from the clamped base at the origin, deflecting along
  x (n̂_1); structure 2 of length l_2 along +x (n̂_1) from the tip of structure 1 (a rigid
  elbow), as in the notation of Fig. 2 and Eqs. 29–33;
- three patches of length 2 in: pair 1 at the root of structure 1 (as published), pair 2 at the
  root of structure 2, pair 3 at mid-span of structure 2 (representative);
- actuator j: equal and opposite moments a_1 u_j at the patch end nodes (moment pair);
  sensor j: a_2 × the surface bending strain averaged over the patch,
  ε_j = (t/2)(θ_b − θ_a)/L_p, so that input and output use the same modal vector (collocation:
  B = Cᵀ × a_1 L_p / (a_2 t/2) > 0).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.dynamics.structural import StructuralPlant
from flexsat.input_checks import FieldError, require_count, require_finite, require_nonneg
from flexsat.structures.fem import FEModes, Structure
from flexsat.structures.modal_model import ModalModel
from flexsat.structures.mode_description import classify_modes
from flexsat.structures.sections import Material, Section
from flexsat.units import to_si

if TYPE_CHECKING:
    import control

SOURCE = CASES["agrawal_bang"].source

#: what Agrawal & Bang 1996 prints about the structure and the control
#: problem (no dimension or frequency)
PUBLISHED: dict[str, Any] = {
    "n_modes": 3,  # §4 "three flexible modes are included"
    "n_pairs": 3,  # §4 three collocated sensor/actuator pairs
    "actuator_1": "root of the first structure",  # §4
    "control_weight": 1e-8,  # §4 Q
    "weights": ((100, 100), (500, 100), (100, 500)),  # §4 (w_1, w_2)
    "initial_gain": 100.0,  # Tables 1-3, every g_ij
}

#: representative patch placement: (structure 1 or 2, start of the patch from that structure's root)
DEFAULT_PATCHES = ((1, "0 m"), (2, "0 m"), (2, "0.3746 m"))

#: the overridable inputs of the case, defaults as written
_INPUTS = {
    "beam1_length": Param("1.0 m", "m"),
    "beam2_length": Param("0.8 m", "m"),
    "width": Param("2 in", "m"),  # out of plane
    "thickness": Param("0.125 in", "m"),  # in plane: the bending dimension
    "modulus": Param("68.9 GPa", "Pa"),
    "density": Param("2700 kg/m**3", "kg/m**3"),
    "tip_mass": Param("0 kg", "kg", "nonneg"),
    "damping": Param(0.005, rule="nonneg"),
    "n_modes": Param(PUBLISHED["n_modes"], rule="count", limit="MAX_MODES"),
    "element_length": Param("0.025 m", "m"),
    "patch_length": Param("2 in", "m"),
    "patches": Param(DEFAULT_PATCHES, rule="raw"),  # checked against the lengths: _patches
    "actuator_gain": Param(1.0),
    "sensor_gain": Param(1.0),
}


@dataclass(frozen=True)
class PiezoPair:
    """One collocated piezoelectric pair (modal vectors over the modal model's modes).

    ``actuator``: modal force of a unit input, a_1 (Φ_r,b − Φ_r,a)ᵀ e_z (moment pair, N m per
    unit input times a_1); ``sensor``: output row, a_2 (t/2)/L_p (Φ_r,b − Φ_r,a)ᵀ e_z (strain
    times a_2); ``ratio`` = actuator / sensor, the same positive number for every mode."""

    name: str
    beam: int
    start: float  # m from the root of its structure
    end: float
    node_a: int
    node_b: int
    actuator: np.ndarray
    sensor: np.ndarray
    ratio: float


@dataclass(frozen=True)
class AgrawalBangCase:
    """The L-shaped two-beam test article (SI); build it with :func:`agrawal_bang`."""

    beam1_length: float
    beam2_length: float
    width: float
    thickness: float
    modulus: float
    density: float
    tip_mass: float
    damping: float
    n_modes: int
    element_length: float
    patch_length: float
    patches: tuple  # ((beam, start), ...), start in m
    actuator_gain: float
    sensor_gain: float
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    # -- geometry and finite elements ---------------------------------------------------------
    @property
    def material(self) -> Material:
        return Material(E=self.modulus, rho=self.density, nu=0.33, name="aluminium")

    @property
    def section(self) -> Section:
        # width along local y is the in-plane (bending) dimension: Iz = w t³ / 12
        return Section.rectangle(self.thickness, self.width, name="strip")

    def _stations(self, beam: int) -> np.ndarray:
        """Node stations along a structure: a uniform grid plus the patch ends (exactly)."""
        L = self.beam1_length if beam == 1 else self.beam2_length
        ends = [x for b, s in self.patches if b == beam for x in (s, s + self.patch_length)]
        grid = np.linspace(0.0, L, int(np.ceil(L / self.element_length - 1e-9)) + 1)
        h = L / (grid.size - 1)
        keep = [
            x for x in grid if x in (0.0, L) or min((abs(x - e) for e in ends), default=h) > h / 4
        ]
        return np.unique(np.concatenate([keep, ends]))

    @property
    def _mesh(self) -> dict:
        if "mesh" not in self._cache:
            l1 = self.beam1_length
            s1, s2 = self._stations(1), self._stations(2)
            xyz = [(0.0, s, 0.0) for s in s1] + [(s, l1, 0.0) for s in s2[1:]]
            ids1 = list(range(1, s1.size + 1))
            ids2 = [ids1[-1]] + list(range(s1.size + 1, s1.size + s2.size))
            self._cache["mesh"] = dict(xyz=xyz, ids1=ids1, ids2=ids2, s1=s1, s2=s2)
        return self._cache["mesh"]

    @property
    def base_node(self) -> int:
        return 1

    @property
    def corner_node(self) -> int:
        return self._mesh["ids1"][-1]

    @property
    def tip_node(self) -> int:
        return self._mesh["ids2"][-1]

    def _node_at(self, beam: int, station: float) -> int:
        m = self._mesh
        s, ids = (m["s1"], m["ids1"]) if beam == 1 else (m["s2"], m["ids2"])
        return int(ids[int(np.argmin(np.abs(s - station)))])

    def structure(self) -> Structure:
        """The planar beam2d model, clamped at the base of structure 1."""
        m = self._mesh
        s = Structure("Agrawal-Bang L structure")
        ids = m["ids1"] + m["ids2"][1:]
        for node, xyz in zip(ids, m["xyz"]):
            s.add_node(node, xyz)
        material, section = self.material, self.section
        for label, chain in (("structure 1", m["ids1"]), ("structure 2", m["ids2"])):
            for a, b in zip(chain[:-1], chain[1:]):
                s.add_beam2d(a, b, material, section, label=label)
        if self.tip_mass > 0:
            s.add_mass(self.tip_node, self.tip_mass)
            s.clamp(self.tip_node, ("uz",))  # planar model: the mass's out-of-plane dof
        s.clamp(self.base_node)
        return s

    @property
    def fe_modes(self) -> FEModes:
        """Every finite-element mode (``FEModes``) of the clamped structure."""
        if "modes" not in self._cache:
            asm = self.structure().assemble()
            self._cache["modes"] = asm.modes(asm.n_dofs)
        return self._cache["modes"]

    # -- modal model, piezo pairs, state space -------------------------------------------------
    def modal_model(self, n_modes: int | None = None) -> ModalModel:
        """Cantilevered modal model (reference: the clamped base, the origin); ``n_modes``
        defaults to the case's (3), ``"all"`` keeps every finite-element mode."""
        if "modal" not in self._cache:
            self._cache["modal"] = ModalModel.from_fe(
                self.fe_modes, self.damping, boundary="cantilevered"
            )
        modal = self._cache["modal"]
        if n_modes == "all":
            return modal
        n = self.n_modes if n_modes is None else require_count(n_modes, "n_modes")
        if n > modal.n_modes:
            raise FieldError(
                "n_modes", f"the finite-element model has {modal.n_modes} modes, got {n}"
            )
        return modal.truncate(n)

    def piezo_pairs(self, n_modes: int | None = None) -> tuple[PiezoPair, ...]:
        """The three collocated pairs: actuator influence (moment pair between the patch end
        nodes, times a_1) and sensor row (strain on the same nodes, times a_2)."""
        modal = self.modal_model(n_modes)
        strain_per_rotation = self.thickness / 2 / self.patch_length
        pairs = []
        for j, (beam, start) in enumerate(self.patches):
            a, b = self._node_at(beam, start), self._node_at(beam, start + self.patch_length)
            pairs.append(
                PiezoPair(
                    name=f"pair {j + 1}",
                    beam=beam,
                    start=start,
                    end=start + self.patch_length,
                    node_a=a,
                    node_b=b,
                    actuator=self.actuator_gain * modal.moment_pair(a, b, "z"),
                    sensor=self.sensor_gain * strain_per_rotation * modal.strain_output(a, b, "z"),
                    ratio=self.actuator_gain / (self.sensor_gain * strain_per_rotation),
                )
            )
        return tuple(pairs)

    def to_statespace(self, n_modes: int | None = None) -> control.StateSpace:
        """python-control StateSpace, state [η, η'], inputs u_1..u_3 (actuator commands, moment
        a_1 u_j), outputs y_1..y_3 (a_2 × patch strain)."""
        import control

        modal = self.modal_model(n_modes)
        pairs = self.piezo_pairs(n_modes)
        sys = modal.to_statespace(
            [p.actuator for p in pairs], [(p.sensor, "displacement") for p in pairs]
        )
        m = modal.n_modes
        return control.ss(
            sys.A,
            sys.B,
            sys.C,
            sys.D,
            states=[f"eta[{i}]" for i in range(m)] + [f"eta_dot[{i}]" for i in range(m)],
            inputs=[f"u{j + 1}" for j in range(len(pairs))],
            outputs=[f"y{j + 1}" for j in range(len(pairs))],
        )

    def _channel_specs(self, node):
        """Actuator and sensor specs of the three pairs, at ``node(n)`` (a node, or its rz dof)."""
        from flexsat.dynamics.structural import Actuator, Sensor

        strain_per_rotation = self.thickness / 2 / self.patch_length
        acts, sensors, rates = [], [], []
        for j, (beam, start) in enumerate(self.patches, start=1):
            ends = (
                node(self._node_at(beam, start)),
                node(self._node_at(beam, start + self.patch_length)),
            )
            axis = "z" if isinstance(ends[0], (int, np.integer)) else None
            acts.append(Actuator(f"u{j}", "moment_pair", ends, axis, self.actuator_gain, "V"))
            gain = self.sensor_gain * strain_per_rotation
            sensors.append(Sensor(f"y{j}", "strain", ends, axis, gain, unit="V"))
            rates.append(Sensor(f"y{j}_dot", "strain", ends, axis, gain, rate=True, unit="V/s"))
        return acts, sensors + rates

    def plant(self, n_modes: int | None = None, coordinates: str = "modal") -> StructuralPlant:
        """The structure as a :class:`~flexsat.dynamics.structural.StructuralPlant`: inputs
        ``u1`` … ``u3`` (the pair voltages V_c, moment pairs a_1 V_c, Eq. 36), outputs ``y1`` …
        ``y3`` (a_2 × patch strain, Eq. 37, the sensors of :meth:`piezo_pairs`) and their rates
        ``y1_dot`` …. ``coordinates="modal"``: the modal model of :meth:`modal_model`
        (``n_modes`` modes, modal damping); ``"fe"``: the clamped finite-element model itself
        (M, K of the assembly, undamped; ``n_modes`` must be None)."""
        if coordinates == "modal":
            acts, sensors = self._channel_specs(lambda n: n)
            return StructuralPlant.from_modal_model(self.modal_model(n_modes), acts, sensors)
        if coordinates != "fe":
            raise FieldError("coordinates", f"must be 'modal' or 'fe', got {coordinates!r}")
        if n_modes is not None:
            raise FieldError(
                "n_modes",
                "the finite-element plant keeps every dof; use coordinates='modal' to truncate",
            )
        asm = self.structure().assemble()
        acts, sensors = self._channel_specs(lambda n: (n, "rz"))
        return StructuralPlant.from_fe(
            asm.M, asm.K, acts, sensors, dofs=asm.dofs, fixed=[(self.base_node, "rz")]
        )

    def tip_outputs(self, n_modes: int | None = None) -> np.ndarray:
        """Rows (4, m) giving ζ_t = [y_1ᵗ, α, y_2ᵗ, β] of Eq. 35 from η (small deflections).

        y_1ᵗ = u_x(corner) (n̂_1); α = ∂y_1/∂x_1 at the corner = −θ_z(corner) (x_1 runs along
        n̂_2, y_1 along n̂_1); y_2ᵗ along b̂_2 ≈ −n̂_2 relative to the rotated structure 2,
        y_2ᵗ = −(u_y(tip) − u_y(corner)) − l_2 α; β = α-relative tip slope = −θ_z(tip) − α.
        Then Eᵗ of Eq. 33 is (y_1ᵗ, −l_2 α − y_2ᵗ)."""
        modal = self.modal_model(n_modes)
        c, t = self.corner_node, self.tip_node
        ux_c = modal.displacement_output(c, "x")
        uy_c, uy_t = modal.displacement_output(c, "y"), modal.displacement_output(t, "y")
        alpha = -modal.rotation_output(c, "z")
        beta = -modal.rotation_output(t, "z") - alpha
        y2 = -(uy_t - uy_c) - self.beam2_length * alpha
        return np.vstack([ux_c, alpha, y2, beta])

    def tip_weight(self, w1: float, w2: float) -> np.ndarray:
        """Q̄ of Eq. 35 for ζ_t = [y_1ᵗ, α, y_2ᵗ, β] (l_2 = ``beam2_length``)."""
        w1, w2 = float(require_finite(w1, "w1")), float(require_finite(w2, "w2"))
        l2 = self.beam2_length
        return np.array(
            [[1.0, 0, 0, 0], [0, w1 * l2**2 + w2, w1 * l2, w2], [0, w1 * l2, w1, 0], [0, w2, 0, w2]]
        )

    # -- the case protocol ---------------------------------------------------------------------
    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        """First ``n_modes`` natural frequencies of the clamped structure, Hz."""
        return self.modal_model(n_modes).frequencies_hz

    def mode_descriptions(self, n_modes: int) -> list[str]:
        """In-plane bending of the L, with each structure's share of the modal kinetic energy
        (the corner node counts with structure 1)."""
        m = self._mesh
        groups = {"structure 1": m["ids1"], "structure 2": m["ids2"][1:]}
        n = require_count(n_modes, "n_modes")
        return [
            f"in-plane bending: structure 1 {d.shares['structure 1']:.0%}, "
            f"structure 2 {d.shares['structure 2']:.0%} of the kinetic energy"
            for d in classify_modes(self.fe_modes, groups)[:n]
        ]

    def mode_details(self, n_modes: int) -> dict:
        """Patch nodes and the modal actuator influence of each pair (a_1 = 1 units)."""
        pairs = self.piezo_pairs(n_modes)
        return {
            "patches": [
                {
                    "name": p.name,
                    "structure": p.beam,
                    "start_m": p.start,
                    "end_m": p.end,
                    "nodes": [p.node_a, p.node_b],
                    "actuator": p.actuator.tolist(),
                }
                for p in pairs
            ],
            "mass_kg": self.modal_model().total_mass,
            "published_frequencies": "none (Agrawal & Bang 1996 prints no frequency of its model)",
        }


def _patches(raw, beam_lengths, patch_length) -> tuple:
    try:
        items = [tuple(p) for p in raw]
    except TypeError:
        items = None
    if items is None or len(items) != 3 or any(len(p) != 2 for p in items):
        raise FieldError("patches", f"must be three (structure, start) pairs, got {raw!r}")
    out = []
    for j, (beam, start) in enumerate(items):
        if isinstance(beam, bool) or beam not in (1, 2):
            raise FieldError(f"patches[{j}]", f"structure must be 1 or 2, got {beam!r}")
        s = float(require_nonneg(to_si(start, "m", f"patches[{j}]"), f"patches[{j}]"))
        L = beam_lengths[beam - 1]
        if s + patch_length > L * (1 + 1e-12):
            raise FieldError(
                f"patches[{j}]",
                f"the patch [{s}, {s + patch_length}] m runs past the "
                f"end of structure {beam} ({L} m)",
            )
        out.append((int(beam), s))
    for i in range(3):
        for j in range(i):
            (bi, si), (bj, sj) = out[i], out[j]
            if bi == bj and abs(si - sj) < patch_length:
                raise FieldError(f"patches[{i}]", f"overlaps patches[{j}] on structure {bi}")
    return tuple(out)


def agrawal_bang(**overrides: Any) -> AgrawalBangCase:
    """Build the L-structure case; override any input by name, as a number (SI) or a unit
    string; ``patches`` is three (structure 1|2, start from that structure's root) pairs.

    >>> case = agrawal_bang(beam2_length="0.6 m", patches=[(1, 0), (1, "0.5 m"), (2, 0)])
    """
    values = read_inputs("agrawal_bang", _INPUTS, overrides)
    if values["damping"] >= 1:
        raise FieldError(
            "damping", f"must be < 1 (a ratio of critical damping), got {values['damping']!r}"
        )
    for name in ("element_length", "patch_length"):
        shortest = min(values["beam1_length"], values["beam2_length"])
        if values[name] > shortest:
            raise FieldError(
                name, f"must not exceed the shorter structure ({shortest} m), got {values[name]} m"
            )
    values["patches"] = _patches(
        values["patches"], (values["beam1_length"], values["beam2_length"]), values["patch_length"]
    )
    case = AgrawalBangCase(**values)
    case.modal_model()  # assemble and solve now: one clear message at construction
    return case


__all__ = ["AgrawalBangCase", "DEFAULT_PATCHES", "PUBLISHED", "PiezoPair", "SOURCE", "agrawal_bang"]
