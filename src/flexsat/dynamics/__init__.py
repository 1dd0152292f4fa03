"""Plants and their kernels.

:mod:`flexsat.dynamics.attitude` (attitude kinematics: Euler parameters, DCM, 1-2-3 Euler
angles, Gibbs and modified Rodrigues parameters) and :mod:`flexsat.dynamics.rigid_body`
(Euler's equations, the norm-preserving step, the Euler–Poinsot solution) are plain
array kernels with a leading case axis; so is :mod:`flexsat.dynamics.cmg` (the single-gimbal
CMG pyramid: momentum, Jacobian, gain, envelope, singularities, steering, null motion),
imported as a module (``from flexsat.dynamics import cmg``) since its short names
(``momentum``, ``gain``) would be ambiguous here. The plants: :mod:`flexsat.dynamics.structural`
(any M, D, K structure with named force, torque and moment-pair inputs),
:mod:`flexsat.dynamics.orbit` (Bainum's beam in orbit), :class:`RigidSpacecraft` and
:class:`FlexibleSpacecraft` (three-axis, the latter in hybrid coordinates; both linearised in
attitude-error coordinates by :func:`linearize_attitude`),
:class:`CmgSpacecraft` (a rigid body steered by a CMG pyramid), :class:`GimbalCluster` (the
pyramid's gimbal kinematics σ̇ = u), :class:`SpaceStation` (the LVLH station model),
:class:`TetheredSubsatellite` (Vadali & Kim's tether, with :class:`TetherScales`) and
:class:`StateSpacePlant` (any x' = Ax + Bu, y = Cx + Du). Their names are
re-exported here and imported from their modules on first use, so importing the package loads
nothing.
"""

from flexsat.lazy import lazy_exports

_EXPORTS = {
    **{
        name: "attitude"
        for name in (
            "cross_matrix",
            "omega_matrix",
            "quaternion_rate_matrix",
            "quaternion_to_dcm",
            "dcm_to_quaternion",
            "euler123_to_dcm",
            "euler123_to_quaternion",
            "dcm_to_euler123",
            "principal_rotation_to_quaternion",
            "quaternion_to_principal_rotation",
            "quaternion_multiply",
            "quaternion_exp",
            "quaternion_to_gibbs",
            "gibbs_to_quaternion",
            "quaternion_to_mrp",
            "mrp_to_quaternion",
            "mrp_shadow",
            "gibbs_rate",
            "mrp_rate",
        )
    },
    **{
        name: "rigid_body"
        for name in (
            "require_inertia",
            "rkmk4_step",
            "dexpinv",
            "cross3",
            "matvec",
            "euler_acceleration",
            "euler_rates",
            "angular_momentum_inertial",
            "kinetic_energy",
            "euler_poinsot_rates",
        )
    },
    "require_shape": "attitude",
    "case_shape": "attitude",
    "require_quaternion": "attitude",
    **{name: "structural" for name in ("StructuralPlant", "Actuator", "Sensor", "ModalBlocks")},
    "BeamInOrbit": "orbit",
    "RigidSpacecraft": "rigid_spacecraft",
    "FlexibleSpacecraft": "flexible_spacecraft",
    "AttitudeLinearization": "attitude_linearization",
    "linearize_attitude": "attitude_linearization",
    "TetheredSubsatellite": "tether",
    "TetherScales": "tether",
    "CmgSpacecraft": "cmg_actuator",
    "GimbalCluster": "gimbal_cluster",
    "SpaceStation": "space_station",
    "StateSpacePlant": "state_space",
}

__all__ = list(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
