r"""Full-state feedback u = −K x as a controller (python-control's convention: ``lqr`` returns
the K of u = −K x; B. D. O. Anderson and J. B. Moore, *Optimal Control: Linear Quadratic
Methods*, Prentice Hall 1990, §2.4).

The law reads a plant's ``state`` output (or another output named by ``reads``) and writes one
input channel; a continuous state feedback, it runs in the engine's continuous-law mode as in
the sampled one.
"""

from __future__ import annotations

import numpy as np

from flexsat.control.base import Controller
from flexsat.input_checks import require_finite

__all__ = ["StateFeedback"]


class StateFeedback(Controller):
    """u = −K y, y the output ``reads`` (default the whole ``state``).

    Parameters
    ----------
    K : array_like (m, n)
        Gain; m the width of the written channel (or the number of written channels), n that
        of the read output.
    writes : str or tuple of str
        The input channel written (default ``torque``), or m scalar channels, one per row of
        K (a plant with one input channel per actuator).
    reads : str
        The output read (default ``state``).
    """

    def __init__(self, K, writes: str | tuple[str, ...] = "torque", reads: str = "state"):
        self.K = require_finite(K, "K")
        if self.K.ndim != 2:
            raise ValueError(f"K: must be a matrix (m, n), got shape {self.K.shape}")
        self.reads = (reads,)
        self.writes = (writes,) if isinstance(writes, str) else tuple(writes)
        if len(self.writes) > 1 and len(self.writes) != self.K.shape[0]:
            raise ValueError(
                f"writes: {len(self.writes)} scalar channels for the {self.K.shape[0]} rows of K"
            )
        self.target = 0.0

    def __call__(self, t, y, state):
        x = np.asarray(y[self.reads[0]], float)
        if x.shape[-1] != self.K.shape[1]:
            raise ValueError(
                f"K: {self.K.shape[1]} columns for the {x.shape[-1]} entries of {self.reads[0]!r}"
            )
        u = -(x @ self.K.T)
        if len(self.writes) > 1:
            return {name: u[..., i] for i, name in enumerate(self.writes)}, state
        return (u[..., 0] if self.K.shape[0] == 1 else u), state
