r"""Force/torque decoupling of point-force actuators (EPS slew study c. 1989, Eqs. 32–37,
"Force/Torque Decoupling").

The point forces :math:`F_i` (N, along body axes at nodes) of a frequency-shaped perturbation
law should damp the elastic modes without turning the vehicle: their net moment about the
centre of mass must vanish,

.. math::

    W F = \sum_i \tilde r_i S_i F = 0, \qquad W = G = [(r_i - c)\times e_i]_i \quad (3\times n_F)

(Eq. 32; G is :attr:`FlexibleSpacecraft.force_moments
<flexsat.dynamics.flexible_spacecraft.FlexibleSpacecraft>`, the torquers' columns of W are
zero). The paper imposes it on the highest derivative :math:`\delta u_3` of the shaped inputs
with zero initial conditions, through a multiplier κ (Eqs. 33–34), which makes the control
weight's inverse the singular projector-like

.. math::

    M_W = R^{-1} - R^{-1}W^T(WR^{-1}W^T)^{-1}WR^{-1} = Z(Z^TRZ)^{-1}Z^T, \qquad W M_W = 0,

Z an orthonormal basis of the null space of W (verified; Eqs. 35–37 with
:math:`\hat R^{-1} := M_W`). Two errata of the paper:

* Eq. 35 prints :math:`\hat R = R + \tfrac12 W^T(WR^{-1}W^T)^{-1}W`; its inverse is not
  :math:`M_W` and :math:`W\hat R^{-1} \ne 0`: it does not enforce the constraint.
* In the full augmented coordinates [δx, δu₁, δu₂] the Riccati equation (35) has no
  stabilising solution: :math:`W\delta u_1` and :math:`W\delta u_2` are integrators no input
  reaches (every admissible δu₃ has Wδu₃ = 0), eigenvalues at 0 that are neither
  controllable nor stable.

So the constraint is built in before augmenting: :math:`\delta u_k = S v_k` with
S = blockdiag(I₃, Z) (torquers unconstrained, forces in the moment-free subspace), and the
frequency-shaped LQR is designed on (A, B S) with weight SᵀDS, standard data; the physical
commands :math:`\delta F = Z v_1` then satisfy W δF = 0 to round-off, and on the admissible
set the law is Eq. 37's with :math:`M_W`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg

from flexsat.input_checks import FieldError, require_finite

if TYPE_CHECKING:
    import numpy.typing as npt

    from flexsat.units import FloatArray

__all__ = ["decoupled_input_map", "moment_free_forces"]


def moment_free_forces(moments: npt.ArrayLike) -> FloatArray:
    r"""Z: orthonormal basis (n_F, n_F − rank G) of the force combinations with zero net
    moment, :math:`GZ = 0` (module docstring; the SVD's null space, rank at the default
    tolerance max(n) ε σ_max).

    Parameters
    ----------
    moments : array_like (3, n_F)
        G, the moment arms (r_i − c) × e_i of the forces about the centre of mass, m.

    Raises
    ------
    ValueError
        When no force combination is moment-free (n_F ≤ rank G): decoupled forces would be
        zero.
    """
    G = require_finite(moments, "moments")
    if G.ndim != 2 or G.shape[0] != 3 or G.shape[1] == 0:
        raise FieldError("moments", f"must have shape (3, n_F) with n_F >= 1, got {G.shape}")
    Z = scipy.linalg.null_space(G)
    if Z.shape[1] == 0:
        raise FieldError(
            "moments",
            f"the {G.shape[1]} forces have no combination with zero net "
            f"moment (rank {np.linalg.matrix_rank(G)} = n_F): decoupled forces "
            f"would all be zero; add force actuators (pairs with opposite moments)",
        )
    return Z


def decoupled_input_map(moments: npt.ArrayLike, n_torques: int = 3) -> FloatArray:
    """S = blockdiag(I, Z) (n_torques + n_F, n_torques + dim null G): physical inputs
    [δu_τ, δF] = S [v_τ, v_F] with the torquers free and the forces moment-free
    (:func:`moment_free_forces`)."""
    Z = moment_free_forces(moments)
    return scipy.linalg.block_diag(np.eye(n_torques), Z)
