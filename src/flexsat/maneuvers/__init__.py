"""Open-loop rigid-body reference maneuvers (torque shapes)."""

from flexsat.maneuvers.torque_shapes import (
    BangBang,
    PseudoSquare,
    Reference,
    Sinusoidal,
    SmoothBangBang,
    TorqueShape,
)

__all__ = ["BangBang", "PseudoSquare", "Reference", "Sinusoidal", "SmoothBangBang", "TorqueShape"]
