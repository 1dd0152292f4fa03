"""Analysis tools on linear models (numpy arrays, python-control conventions)."""

from flexsat.analysis.controllability import (
    FrequencyGroup,
    RepeatedFrequencyResult,
    controllability_matrix,
    controllability_rank,
    is_stabilizable,
    lqr_gain,
    pbh_test,
    repeated_frequency_test,
)

__all__ = ["FrequencyGroup", "RepeatedFrequencyResult", "controllability_matrix",
           "controllability_rank", "is_stabilizable", "lqr_gain", "pbh_test",
           "repeated_frequency_test"]
