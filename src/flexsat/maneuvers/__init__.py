"""Open-loop rigid-body reference maneuvers (torque shapes, frequency-shaped optimal slew)."""

from flexsat.maneuvers.frequency_shaped_slew import (
    FrequencyShapedSlew,
    frequency_shaped_slew,
)
from flexsat.maneuvers.three_axis_slew import (
    ContinuationStep,
    ThreeAxisSlew,
    three_axis_slew,
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
    "ContinuationStep",
    "FrequencyShapedSlew",
    "PseudoSquare",
    "Reference",
    "Sinusoidal",
    "SmoothBangBang",
    "ThreeAxisSlew",
    "TorqueShape",
    "frequency_shaped_slew",
    "three_axis_slew",
]
