"""Simulation engine: sampled-data control, sensors, actuators, disturbances, batch runs."""

from flexsat.sim.actuators import TorqueActuator
from flexsat.sim.disturbances import BearingFriction, Impulses, RandomTorque
from flexsat.sim.engine import SimConfig, SimResult, SimulationDiverged, simulate
from flexsat.sim.sensors import Sensors

__all__ = ["BearingFriction", "Impulses", "RandomTorque", "SimConfig", "SimResult", "SimulationDiverged", "Sensors",
           "TorqueActuator", "simulate"]
