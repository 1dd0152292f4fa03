"""Open-loop rigid-body reference maneuvers (torque shapes, frequency-shaped optimal slew)."""

from flexsat.maneuvers.frequency_shaped_slew import (
    FrequencyShapedSlew,
    frequency_shaped_slew,
)
from flexsat.maneuvers.torque_shapes import (
    BangBang,
    PseudoSquare,
    Reference,
    Sinusoidal,
    SmoothBangBang,
    TorqueShape,
)

__all__ = [
    "BangBang",
    "FrequencyShapedSlew",
    "PseudoSquare",
    "Reference",
    "Sinusoidal",
    "SmoothBangBang",
    "TorqueShape",
    "frequency_shaped_slew",
]
