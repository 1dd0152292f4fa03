"""Control laws behind one interface (:class:`Controller`)."""

from flexsat.control.base import Controller
from flexsat.control.lyapunov import LyapunovRegulator, LyapunovTracker, check_lyapunov_gains
from flexsat.control.pd import PD

__all__ = ["Controller", "LyapunovRegulator", "LyapunovTracker", "PD", "check_lyapunov_gains"]
