"""Analysis tools on linear models (numpy arrays, python-control conventions)."""

from flexsat.analysis.controllability import (
    FrequencyGroup,
    RepeatedFrequencyResult,
    controllability_matrix,
    controllability_rank,
    is_stabilizable,
    pbh_test,
    repeated_frequency_test,
)

from flexsat.analysis.gramians import (
    finite_horizon_gramian,
    gawronski_gramians,
    lyapunov_gramian,
    modal_controllability_gramian,
    modal_gramian,
    modal_observability_gramian,
)
from flexsat.analysis.homotopy import HomotopyResult, HomotopyStep, homotopy_minimize
from flexsat.analysis.placement import (
    exchange,
    exhaustive,
    gawronski_index,
    greedy,
    h2_actuator_ranking,
    h2_placement,
    hamdan_nayfeh,
    kim_junkins_index,
    modal_controllability,
    modal_cost,
)
from flexsat.analysis.sensitivity import (
    EigenDerivatives,
    ModalDerivatives,
    SVDDerivatives,
    condition_number_derivatives,
    eig_derivatives,
    eigenvector_condition_derivatives,
    modal_derivatives,
    svd_derivatives,
)

__all__ = ["EigenDerivatives", "HomotopyResult", "HomotopyStep", "ModalDerivatives",
           "SVDDerivatives", "condition_number_derivatives", "eig_derivatives",
           "eigenvector_condition_derivatives", "homotopy_minimize", "modal_derivatives",
           "svd_derivatives",
           "FrequencyGroup", "RepeatedFrequencyResult", "controllability_matrix",
           "controllability_rank", "exchange", "exhaustive", "finite_horizon_gramian",
           "gawronski_gramians", "gawronski_index", "greedy", "h2_actuator_ranking",
           "h2_placement", "hamdan_nayfeh", "is_stabilizable", "kim_junkins_index",
           "lyapunov_gramian", "modal_controllability", "modal_controllability_gramian",
           "modal_cost", "modal_gramian", "modal_observability_gramian", "pbh_test",
           "repeated_frequency_test"]
