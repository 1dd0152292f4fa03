"""NASA LaRC Earth Pointing Satellite (EPS) structure (EPS slew study c. 1989, "Model Development").

The published data ("Model Development") are entered in ``PUBLISHED``
exactly as printed and converted with
pint.  The NASTRAN deck (95 nodes, 223 elements, by J. Walz) is not reproduced and Fig. 1 is lost,
so the geometry below is a reconstruction; every choice is a parameter and is argued in
docs/eps.md.

Reconstruction (defaults)
-------------------------
- Axes: x along the truss, y the antenna boresight (antennas on the +y side of the truss),
  z = x × y.  With this frame the paper's labels "z-rotation" / "x-rotation" of an antenna are
  rotations about the truss-normal in-plane axis and about the truss axis.
- Truss: square 3 m × 3 m section, 25 m long, 10 bays of 2.5 m: 11 frames of 4 nodes (44 nodes),
  4 longerons per bay, 4 battens and one in-plane diagonal per frame, one diagonal per face per
  bay (alternating): 40 + 44 + 11 + 40 = **135 tubes**, the published count.
- Antennas: 12 ribs from a hub node, 2 elements per rib, hoop elements between the rib ends,
  i.e. 25 nodes and 36 elements per antenna; a shallow paraboloid of depth D/16 (f/D = 1).
  Hub over the middle of the first (15 m) and last (7.5 m) bay.
- Supports: 4 tubes per antenna from the four +y-face nodes of that bay to the hub, hub offset
  3.5 m (15 m antenna) and 5 m (7.5 m antenna) from the truss face.
- Non-structural mass (329.63 kg) split between the antennas by aperture area (80 % / 20 %) and
  lumped on the antenna nodes by tributary (projected) area.
- Torquers: node at the centre of mass of the whole vehicle (found by fixed-point iteration),
  joined to the nearest truss face panel by 4 tubes; its mass balances the total to the
  published 1028 kg (``actuator_mass="balance"``), the published 150 kg being reported beside.
- With these defaults the node numbers are the paper's: 1-44 truss, 45 hub / 46-57 mid-rib /
  58-69 rim of the 15 m antenna, 70 / 71-82 / 83-94 of the 7.5 m antenna, 95 the CG.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from flexsat import limits
from flexsat.cases.inputs import Param, read_inputs
from flexsat.catalog import CASES
from flexsat.input_checks import FieldError, require_count, require_nonneg
from flexsat.structures.mode_description import classify_modes
from flexsat.structures.sections import Material, Section
from flexsat.units import to_si

if TYPE_CHECKING:
    from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft
    from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft
    from flexsat.structures.fem import Assembly, FEModes, MassProperties, Structure
    from flexsat.structures.modal_model import ModalModel

SOURCE = CASES["eps"].source

#: The EPS data exactly as published ("Model Development")
PUBLISHED: dict[str, Any] = {
    "total_mass": "1028 kg",
    "structural_mass": "548 kg",
    "nonstructural_mass": "329.63 kg",
    "actuator_mass": "150 kg",
    "truss_length": "25 m",
    "truss_cross_section": "3 m",
    "truss_elements": 135,
    "large_antenna_diameter": "15 m",
    "small_antenna_diameter": "7.5 m",
    "ribs": 12,
    "support_elements": 4,
    "tube_outer_diameter": "51 mm",
    "tube_wall": "1.59 mm",
    "modulus": "275.9E+09 N/m**2",
    "density": "3250 kg/m**3",
    "modal_damping": "0.5 %",
    "first_truss_mode": "7.0 Hz",
    "first_truss_mode_number": 50,
    "nastran_nodes": 95,
    "nastran_elements": 223,
}

#: "Model Development": (mode number, frequency, description) as
#: printed; modes 1-6 are rigid (0.0 Hz)
PUBLISHED_MODES = (
    (7, "0.2422 Hz", "Torsion of 15 m Antenna"),
    (8, "0.4056 Hz", "z-rotation 15 m Antenna"),
    (9, "0.5652 Hz", "x-rotation 15 m Antenna"),
    (10, "0.6562 Hz", "Torsion 7.5m Antenna"),
    (11, "0.8882 Hz", "15 m Antenna mode"),
    (12, "0.8882 Hz", "15 m Antenna mode"),
    (13, "1.4377 Hz", "z-rotation 7.5 m Antenna"),
    (14, "1.5360 Hz", "x-rotation 7.5 m Antenna"),
    (15, "1.7762 Hz", "15 m Antenna mode"),
    (16, "1.7762 Hz", "15 m Antenna mode"),
    (17, "3.0258 Hz", "15 m Antenna mode"),
    (18, "3.0258 Hz", "15 m Antenna mode"),
    (19, "3.1532 Hz", "15 m Antenna mode"),
    (20, "3.1532 Hz", "15 m Antenna mode"),
)

#: the paper's node numbers ("Actuator Placement", "Perturbation Control - Torquers + Force
#: Actuators, 10 s Maneuver") and the role we give them
NODE_ROLES = {
    60: "15 m antenna rim, 0° (+x, along the truss)",
    63: "15 m antenna rim, 90° (+z)",
    66: "15 m antenna rim, 180° (-x, outboard)",
    69: "15 m antenna rim, 270° (-z)",
    85: "7.5 m antenna rim, 0° (+x, outboard)",
    88: "7.5 m antenna rim, 90° (+z)",
    95: "centre of mass: torquers (actuator support node)",
    52: "candidate: 15 m antenna mid-rib node, 120° [role not stated in the paper]",
    78: "candidate: 7.5 m antenna mid-rib node, 150° [role not stated in the paper]",
    94: "candidate: 7.5 m antenna rim, 270° (-z) [role not stated in the paper]",
}
# role -> (antenna index or None for the CG, fraction of the radius, angle in degrees)
_ROLE_GEOMETRY = {
    60: (0, 1.0, 0),
    63: (0, 1.0, 90),
    66: (0, 1.0, 180),
    69: (0, 1.0, 270),
    85: (1, 1.0, 0),
    88: (1, 1.0, 90),
    52: (0, 0.5, 120),
    78: (1, 0.5, 150),
    94: (1, 1.0, 270),
    95: (None, 0.0, 0),
}

BALANCE = "balance"


def _actuator_mass_input(raw, name: str) -> float | str:
    """A mass (kg, >= 0) or "balance": the rest of ``total_mass``."""
    if isinstance(raw, str) and raw.strip().lower() == BALANCE:
        return BALANCE
    return float(require_nonneg(to_si(raw, "kg", name), name))


#: the overridable inputs of the case, defaults as written
_INPUTS = {
    "truss_length": Param(PUBLISHED["truss_length"], "m"),
    "truss_width": Param(PUBLISHED["truss_cross_section"], "m"),
    "truss_bays": Param(10, rule="count"),
    "tube_outer_diameter": Param(PUBLISHED["tube_outer_diameter"], "m"),
    "tube_wall": Param(PUBLISHED["tube_wall"], "m"),
    "modulus": Param(PUBLISHED["modulus"], "Pa"),
    "density": Param(PUBLISHED["density"], "kg/m**3"),
    "poisson_ratio": Param(0.3),
    "large_antenna_diameter": Param(PUBLISHED["large_antenna_diameter"], "m"),
    "small_antenna_diameter": Param(PUBLISHED["small_antenna_diameter"], "m"),
    "ribs": Param(PUBLISHED["ribs"], rule="count"),
    "rib_elements": Param(2, rule="count"),
    "depth_ratio": Param(1 / 16, rule="nonneg"),
    "large_support_height": Param("3.5 m", "m"),
    "small_support_height": Param("5 m", "m"),
    "large_antenna_bay": Param(1, rule="count"),
    "small_antenna_bay": Param(None, rule="count", optional=True),  # None: the last bay
    "nonstructural_mass": Param(PUBLISHED["nonstructural_mass"], "kg", "nonneg"),
    "large_antenna_share": Param(None, optional=True),  # None: by aperture area
    "actuator_mass": Param(BALANCE, rule=_actuator_mass_input),
    "total_mass": Param(PUBLISHED["total_mass"], "kg"),
    "damping": Param(0.005, rule="nonneg"),
}
_CG_OUTSIDE = 0.25  # m: a CG this far outside the truss gets a 4-tube pyramid, else 8 bay corners


def _published(key: str, unit: str) -> float:
    return to_si(PUBLISHED[key], unit, key)


#: the final point-force actuators of the EPS slew study c. 1989 ("Actuator
#: Placement"): paper node and body axis
FINAL_FORCES = ((69, "x"), (63, "x"), (66, "y"), (66, "z"), (60, "y"), (60, "z"), (88, "x"))
#: antenna rim nodes whose deflections the paper's goals bound (EPS slew study
#: c. 1989, "Simulation Results")
RIM_NODES = (66, 69, 85, 88)


@dataclass(frozen=True)
class _Model:
    """The built structure and its bookkeeping."""

    structure: Structure
    groups: dict
    antenna_nodes: tuple  # per antenna: (hub id, ids by ring (ring, rib) array)
    cg_node: int
    cg: np.ndarray
    budget: dict
    element_counts: dict


@dataclass(frozen=True)
class EPSCase:
    """The EPS structure: geometry and mass parameters (SI), the FE model and its modes."""

    truss_length: float
    truss_width: float
    truss_bays: int
    tube_outer_diameter: float
    tube_wall: float
    modulus: float
    density: float
    poisson_ratio: float
    large_antenna_diameter: float
    small_antenna_diameter: float
    ribs: int
    rib_elements: int
    depth_ratio: float
    large_support_height: float
    small_support_height: float
    large_antenna_bay: int
    small_antenna_bay: int
    nonstructural_mass: float
    large_antenna_share: float
    actuator_mass: float | str
    total_mass: float
    damping: float
    _cache: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    # -- materials ---------------------------------------------------------------------------
    @property
    def material(self) -> Material:
        return Material(self.modulus, self.density, nu=self.poisson_ratio, name="graphite")

    @property
    def section(self) -> Section:
        return Section.tube(self.tube_outer_diameter, self.tube_wall, name="51 x 1.59 mm tube")

    @property
    def mass_per_length(self) -> float:
        return self.density * self.section.A

    @property
    def diameters(self) -> tuple[float, float]:
        return (self.large_antenna_diameter, self.small_antenna_diameter)

    @property
    def group_names(self) -> tuple[str, str]:
        large, small = (f"{d:g} m antenna" for d in self.diameters)
        return (large, small) if large != small else ("large antenna", "small antenna")

    # -- geometry ----------------------------------------------------------------------------
    @cached_property
    def _model(self) -> _Model:
        return _build(self)

    def structure(self) -> Structure:
        """The finite-element model (``flexsat.structures.fem.Structure``)."""
        return self._model.structure

    @cached_property
    def assembly(self) -> Assembly:
        return self._model.structure.assemble()

    @property
    def groups(self) -> dict[str, np.ndarray]:
        """Node ids of the components: truss, the two antennas, torquers (CG node)."""
        return dict(self._model.groups)

    @property
    def node_roles(self) -> dict[int, int]:
        """The paper's node number -> our node id (see ``NODE_ROLES`` for the roles)."""
        model = self._model
        coords = dict(zip(self.assembly.node_ids.tolist(), self.assembly.coordinates))
        roles = {}
        for paper, (antenna, frac, angle) in _ROLE_GEOMETRY.items():
            if antenna is None:
                roles[paper] = model.cg_node
                continue
            hub, rings = model.antenna_nodes[antenna]
            ring = int(round(frac * self.rib_elements)) - 1
            ring = min(max(ring, 0), self.rib_elements - 1)
            want = np.radians(angle)
            best = min(
                rings[ring],
                key=lambda n: abs(
                    np.angle(
                        np.exp(
                            1j
                            * (
                                np.arctan2(
                                    coords[n][2] - coords[hub][2], coords[n][0] - coords[hub][0]
                                )
                                - want
                            )
                        )
                    )
                ),
            )
            roles[paper] = int(best)
        return roles

    # -- modes -------------------------------------------------------------------------------
    def modes(self, n_modes: int) -> FEModes:
        """``FEModes`` of the free-free structure: 6 rigid modes then ``n_modes`` elastic ones."""
        n = require_count(n_modes, "n_modes")
        ndof = len(self.assembly.dofs)
        if n + 6 > ndof:
            raise FieldError("n_modes", f"the model has {ndof - 6} elastic modes, got {n}")
        cached = self._cache.get("modes")
        if cached is None or cached.shapes.shape[1] < n + 6:
            cached = self.assembly.modes(min(max(n + 6, 26), ndof), rigid_body_modes=6)
            self._cache["modes"] = cached
        return cached

    def _classified(self, n_modes: int):
        n = require_count(n_modes, "n_modes")
        key = ("classified", n)
        if key not in self._cache:
            self._cache[key] = classify_modes(_first(self.modes(n), n + 6), self._model.groups)
        return self._cache[key]

    def frequencies_hz(self, n_modes: int) -> np.ndarray:
        """First ``n_modes`` elastic frequencies, Hz."""
        n = require_count(n_modes, "n_modes")
        return np.asarray(self.modes(n).frequencies_hz[6 : 6 + n])

    def mode_descriptions(self, n_modes: int) -> list[str]:
        """One phrase per elastic mode (``flexsat.structures.mode_description``)."""
        return [str(d) for d in self._classified(n_modes)[6:]]

    def rigid_body_descriptions(self) -> list[str]:
        return [str(d) for d in self._classified(1)[:6]]

    def mode_details(self, n_modes: int) -> dict:
        """Published table side by side (paper modes 7-20 = elastic modes 1-14), mass budget and
        node roles, JSON-ready."""
        n = require_count(n_modes, "n_modes")
        ours = self.frequencies_hz(n)
        published: list[float | None] = []
        pub_desc: list[str | None] = []
        ratio: list[float | None] = []
        numbers: list[int] = []
        for i in range(n):
            numbers.append(i + 7)
            if i < len(PUBLISHED_MODES):
                f = to_si(PUBLISHED_MODES[i][1], "Hz", f"mode {i + 7}")
                published.append(f)
                pub_desc.append(PUBLISHED_MODES[i][2])
                ratio.append(float(ours[i] / f))
            else:
                published.append(None)
                pub_desc.append(None)
                ratio.append(None)
        return {
            "paper_mode_number": numbers,
            "published_hz": published,
            "ratio_to_published": ratio,
            "published_descriptions": pub_desc,
            "mass_budget_kg": self.mass_budget(),
            "node_roles": {str(k): v for k, v in self.node_roles.items()},
        }

    def first_truss_mode(self, max_modes: int = 120) -> tuple[int, float, str]:
        """(elastic mode number, frequency Hz, description) of the first mode whose largest
        kinetic-energy share is the truss's, searched among the first ``max_modes``."""
        for d in self._classified(max_modes)[6:]:
            if d.component == "truss":
                return d.index - 5, d.frequency_hz, str(d)
        raise FieldError("max_modes", f"no truss-dominated mode among the first {max_modes}")

    def modal_model(self, n_modes: int = 45) -> ModalModel:
        """``ModalModel`` (flexsat.structures.modal_model) of the 6 rigid + ``n_modes`` elastic
        modes, ``damping`` (0.5 %) on every elastic mode, reference at the CG node."""
        from flexsat.structures.modal_model import ModalModel

        modes = _first(self.modes(n_modes), n_modes + 6)
        zeta = np.r_[np.zeros(6), np.full(n_modes, self.damping)]
        return ModalModel.from_fe(modes, damping=zeta, reference=self._model.cg, boundary="free")

    def plant(
        self,
        model: str = "flexible",
        n_modes: int = 45,
        forces: Sequence[tuple[int, str]] = FINAL_FORCES,
        rim_nodes: Sequence[int] = RIM_NODES,
    ) -> FlexibleSpacecraft | RigidSpacecraft:
        """The spacecraft as a three-axis plant of the simulation core.

        Parameters
        ----------
        model : {"flexible", "rigid"}
            ``"flexible"``: :class:`~flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft`
            in hybrid coordinates on the free-free :meth:`modal_model` (``n_modes`` elastic
            modes), ideal torquers at the CG node (95) loading the modes there, point forces
            ``force_<node><AXIS>`` at the paper's nodes (default the final set of the EPS slew
            study c. 1989, "Actuator Placement": 69X, 63X, 66Y, 66Z, 60Y, 60Z, 88X) and
            the elastic displacements of the
            antenna rims (nodes 66, 69, 85, 88, three axes each); ``"rigid"``:
            :class:`~flexsat.dynamics.rigid_spacecraft.RigidSpacecraft` with the model's
            inertia about its CG (the published inertia set is in :meth:`mass_properties`).
        n_modes : int
            Elastic modes of the flexible model (the paper's plant: 45).
        forces : sequence of (paper node, axis)
            Point-force actuators.
        rim_nodes : sequence of int
            Paper nodes whose displacements are outputs.
        """
        if model == "rigid":
            from flexsat.dynamics.rigid_spacecraft import RigidSpacecraft

            return RigidSpacecraft(self.mass_properties()["inertia_center_of_mass"])
        if model != "flexible":
            raise FieldError("model", f"must be 'flexible' or 'rigid', got {model!r}")
        from flexsat.dynamics.flexible_spacecraft import FlexibleSpacecraft

        roles = self.node_roles

        def node(paper, field):
            if paper not in roles:
                raise FieldError(
                    field, f"{paper!r} is not one of the paper's nodes ({min(roles)}-{max(roles)})"
                )
            return roles[paper]

        points = [(node(int(n), "forces"), str(a).lower()) for n, a in forces]
        rims = [(node(int(n), "rim_nodes"), a) for n in rim_nodes for a in "xyz"]
        n_modes = require_count(n_modes, "n_modes")
        limits.check_count(n_modes, limits.MAX_MODES, "n_modes", "elastic modes of the plant")
        return FlexibleSpacecraft(
            self.modal_model(n_modes),
            forces=points,
            displacements=rims,
            torque_node=roles[95],
        )

    # -- mass --------------------------------------------------------------------------------
    def mass_budget(self) -> dict[str, float]:
        """kg: the model's parts, its total from the assembled mass matrix, the published split."""
        budget = dict(self._model.budget)
        budget["total_assembled"] = float(self.assembly.mass_properties()["total_mass"])
        budget["published_structural"] = _published("structural_mass", "kg")
        budget["published_nonstructural"] = _published("nonstructural_mass", "kg")
        budget["published_actuators"] = _published("actuator_mass", "kg")
        budget["published_total"] = _published("total_mass", "kg")
        return budget

    def mass_properties(self) -> MassProperties:
        """Mass, centre of mass and inertia (about the CG node) from the assembled mass matrix."""
        return self.assembly.mass_properties(self._model.cg)

    @property
    def center_of_mass(self) -> np.ndarray:
        """Position of the torquer node (the centre of mass of the whole model), m."""
        return np.array(self._model.cg)

    @property
    def element_counts(self) -> dict[str, int]:
        """Number of tubes per part: truss, antenna 1/2 (ribs + hoops), support 1/2, actuator
        support."""
        return dict(self._model.element_counts)

    @property
    def n_elements(self) -> int:
        return sum(self._model.element_counts.values())


def _first(modes, n: int):
    """The first n modes of an FEModes (same type)."""
    if modes.shapes.shape[1] == n:
        return modes
    from dataclasses import replace

    return replace(modes, omegas=modes.omegas[:n], shapes=modes.shapes[:, :n])


# ------------------------------------------------------------------------------------------------
# construction
def _build(case: EPSCase) -> _Model:
    from flexsat.structures.fem import Structure

    mat, sec, rho_a = case.material, case.section, case.mass_per_length
    nb, w = case.truss_bays, case.truss_width
    bay = case.truss_length / nb
    h = w / 2
    corners = ((-h, -h), (h, -h), (h, h), (-h, h))  # (y, z); corners 1, 2 form the +y face

    def tid(k, c):
        return 4 * k + c % 4 + 1

    nodes: dict[int, np.ndarray] = {}
    elements: list[tuple[int, int, str]] = []
    lumped: dict[int, float] = {}
    for k in range(nb + 1):
        for c, (y, z) in enumerate(corners):
            nodes[tid(k, c)] = np.array([k * bay, y, z])
    for k in range(nb + 1):
        for c in range(4):
            elements.append((tid(k, c), tid(k, c + 1), "truss"))
        elements.append(
            (tid(k, 0), tid(k, 2), "truss") if k % 2 == 0 else (tid(k, 1), tid(k, 3), "truss")
        )
    for k in range(nb):
        for c in range(4):
            elements.append((tid(k, c), tid(k + 1, c), "truss"))
            elements.append(
                (tid(k, c), tid(k + 1, c + 1), "truss")
                if (k + c) % 2 == 0
                else (tid(k, c + 1), tid(k + 1, c), "truss")
            )
    truss_ids = list(nodes)

    shares = _antenna_shares(case)
    ns_mass = case.nonstructural_mass
    antenna_nodes = []
    groups = {"truss": np.array(truss_ids)}
    next_id = 4 * (nb + 1) + 1
    bays = (case.large_antenna_bay, case.small_antenna_bay)
    heights = (case.large_support_height, case.small_support_height)
    n_r, n_e = case.ribs, case.rib_elements
    for a, (D, b, H) in enumerate(zip(case.diameters, bays, heights)):
        R = D / 2
        hub = next_id
        x_hub, y_hub = (b - 0.5) * bay, h + H
        nodes[hub] = np.array([x_hub, y_hub, 0.0])
        rings = np.zeros((n_e, n_r), dtype=int)
        radii = R * np.arange(1, n_e + 1) / n_e
        for j, r in enumerate(radii):
            for k in range(n_r):
                phi = 2 * np.pi * k / n_r - np.pi / 3  # rib 2 at 0°: the paper's numbering
                nid = hub + 1 + j * n_r + k
                sag = case.depth_ratio * D * (r / R) ** 2  # paraboloid, rim depth D·depth_ratio
                nodes[nid] = np.array([x_hub + r * np.cos(phi), y_hub + sag, r * np.sin(phi)])
                rings[j, k] = nid
        next_id = hub + 1 + n_e * n_r
        label = f"antenna {a + 1}"
        for k in range(n_r):
            chain = [hub] + rings[:, k].tolist()
            for n1, n2 in zip(chain[:-1], chain[1:]):
                elements.append((n1, n2, label))
            elements.append((rings[-1, k], rings[-1, (k + 1) % n_r], label))
        feet = (tid(b - 1, 1), tid(b - 1, 2), tid(b, 1), tid(b, 2))
        for f in feet:
            elements.append((f, hub, f"support {a + 1}"))
        # non-structural mass by tributary (projected) area: node at radius r_j carries the
        # annulus [r_j - dr/2, r_j + dr/2] ∩ [0, R] shared by the ribs; the hub the inner disc
        m_a = ns_mass * shares[a]
        dr = R / n_e
        lumped[hub] = lumped.get(hub, 0.0) + m_a * (dr / 2) ** 2 / R**2
        for j, r in enumerate(radii):
            ring_area = (min(r + dr / 2, R) ** 2 - (r - dr / 2) ** 2) / R**2
            for nid in rings[j]:
                lumped[int(nid)] = lumped.get(int(nid), 0.0) + m_a * ring_area / n_r
        antenna_nodes.append((hub, rings))
        groups[case.group_names[a]] = np.r_[hub, rings.ravel()]

    # torquers at the centre of mass: fixed point of (node position -> support -> CG)
    cg_node = next_id

    def lengths(elems, where):
        return np.array([np.linalg.norm(where[e[1]] - where[e[0]]) for e in elems])

    base_len = lengths(elements, nodes)
    base_mass = rho_a * base_len.sum() + sum(lumped.values())
    base_moment = rho_a * sum(
        L * 0.5 * (nodes[e[0]] + nodes[e[1]]) for L, e in zip(base_len, elements)
    )
    base_moment = base_moment + sum(m * nodes[n] for n, m in lumped.items())
    p = base_moment / base_mass
    for _ in range(200):
        support = _actuator_support(p, nodes, bay, nb, h, tid)
        sup_len = np.array([np.linalg.norm(nodes[f] - p) for f in support])
        structural = rho_a * (base_len.sum() + sup_len.sum())
        act = _actuator_mass(case, structural)
        mass = base_mass + rho_a * sup_len.sum() + act
        moment = base_moment + rho_a * sum(
            L * 0.5 * (nodes[f] + p) for L, f in zip(sup_len, support)
        )
        moment = moment + act * p
        p_new = moment / mass
        if np.linalg.norm(p_new - p) < 1e-12:
            break
        p = p_new
    p = p_new
    support = _actuator_support(p, nodes, bay, nb, h, tid)
    nodes[cg_node] = p
    for f in support:
        elements.append((cg_node, f, "actuator support"))
    groups["torquers"] = np.array([cg_node])

    s = Structure("EPS")
    for nid in sorted(nodes):
        s.add_node(nid, nodes[nid])
    for n1, n2, label in elements:
        s.add_frame(n1, n2, mat, sec, label=label)
    for nid, m in sorted(lumped.items()):
        if m > 0:
            s.add_mass(nid, m)
    act = _actuator_mass(case, structural)
    if act > 0:
        s.add_mass(cg_node, act)

    all_len = lengths(elements, nodes)
    by_label: dict[str, float] = {}
    for L, (_, _, label) in zip(all_len, elements):
        by_label[label] = by_label.get(label, 0.0) + rho_a * L
    budget = {
        "truss": by_label["truss"],
        "antenna_1_structure": by_label["antenna 1"],
        "antenna_2_structure": by_label["antenna 2"],
        "antenna_supports": by_label["support 1"] + by_label["support 2"],
        "actuator_support": by_label["actuator support"],
        "structural": float(rho_a * all_len.sum()),
        "antenna_1_nonstructural": ns_mass * shares[0],
        "antenna_2_nonstructural": ns_mass * shares[1],
        "nonstructural": ns_mass,
        "actuators": act,
        "total": float(rho_a * all_len.sum() + ns_mass + act),
    }
    counts: dict[str, int] = {}
    for _, _, label in elements:
        counts[label] = counts.get(label, 0) + 1
    return _Model(s, groups, tuple(antenna_nodes), cg_node, p, budget, counts)


def _antenna_shares(case: EPSCase) -> tuple[float, float]:
    if case.large_antenna_share is None:
        d1, d2 = case.diameters
        s = d1**2 / (d1**2 + d2**2)
    else:
        s = case.large_antenna_share
    return (s, 1.0 - s)


def _actuator_mass(case: EPSCase, structural: float) -> float:
    if case.actuator_mass != BALANCE:
        return float(case.actuator_mass)
    act = case.total_mass - structural - case.nonstructural_mass
    if act < 0:
        raise FieldError(
            "actuator_mass",
            f"balancing to total_mass = {case.total_mass:g} kg gives {act:.2f} kg "
            f"(structural {structural:.2f} kg + non-structural {case.nonstructural_mass:g} kg "
            "exceed it); give actuator_mass explicitly or raise total_mass",
        )
    return act


def _actuator_support(p, nodes, bay, nb, h, tid) -> list[int]:
    """Truss nodes the CG node is tied to: the 4 corners of the nearest face panel of the bay
    under the CG when the CG is >= 0.25 m outside the truss, else the 8 corners of that bay."""
    k = int(np.clip(np.floor(p[0] / bay), 0, nb - 1))
    y, z = p[1], p[2]
    outside = max(abs(y), abs(z)) - h
    if outside < _CG_OUTSIDE:
        return [tid(kk, c) for kk in (k, k + 1) for c in range(4)]
    if abs(y) >= abs(z):
        face = (1, 2) if y > 0 else (3, 0)
    else:
        face = (2, 3) if z > 0 else (0, 1)
    return [tid(kk, c) for kk in (k, k + 1) for c in face]


# ------------------------------------------------------------------------------------------------
def eps(**overrides: Any) -> EPSCase:
    """Build the EPS case; override any input by name, as a number (SI) or a unit string.

    >>> case = eps(small_support_height="4 m", nonstructural_mass="300 kg")  # doctest: +SKIP
    """
    values = read_inputs("eps", _INPUTS, overrides)
    nb = values["truss_bays"]
    if values["small_antenna_bay"] is None:
        values["small_antenna_bay"] = nb
    for name in ("large_antenna_bay", "small_antenna_bay"):
        if values[name] > nb:
            raise FieldError(name, f"must be a bay number 1..truss_bays = {nb}, got {values[name]}")
    if values["large_antenna_bay"] == values["small_antenna_bay"]:
        raise FieldError(
            "small_antenna_bay",
            f"must differ from large_antenna_bay (both {values['large_antenna_bay']})",
        )
    if values["ribs"] < 3:
        raise FieldError("ribs", f"must be >= 3, got {values['ribs']}")
    share = values["large_antenna_share"]
    if share is not None and not 0 <= share <= 1:
        raise FieldError("large_antenna_share", f"must be in [0, 1], got {share!r}")
    if not values["poisson_ratio"] < 0.5:
        raise FieldError("poisson_ratio", f"must be < 0.5, got {values['poisson_ratio']!r}")
    if not values["damping"] < 1:
        raise FieldError("damping", f"must be a modal damping ratio < 1, got {values['damping']!r}")
    if values["tube_wall"] > values["tube_outer_diameter"] / 2:
        raise FieldError(
            "tube_wall",
            "must be <= tube_outer_diameter / 2 "
            f"= {values['tube_outer_diameter'] / 2:g} m, "
            f"got {values['tube_wall']:g} m",
        )
    case = EPSCase(**values)
    case._model  # noqa: B018 -- build now: one clear message at construction
    return case


__all__ = ["BALANCE", "EPSCase", "NODE_ROLES", "PUBLISHED", "PUBLISHED_MODES", "SOURCE", "eps"]
