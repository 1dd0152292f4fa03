"""Simulation engine: sampled-data control of any plant, per-channel sensors, actuators and
disturbances (with the single-axis presets), batch and dispersed runs."""

from flexsat.sim.actuators import TorqueActuator
from flexsat.sim.channels import ChannelActuator, ChannelDisturbance, ChannelSensor
from flexsat.sim.config import StopCondition
from flexsat.sim.disturbances import BearingFriction, Impulses, RandomTorque
from flexsat.sim.engine import SimConfig, SimResult, SimulationDiverged, simulate
from flexsat.sim.sensors import Sensors

__all__ = [
    "BearingFriction",
    "ChannelActuator",
    "ChannelDisturbance",
    "ChannelSensor",
    "Impulses",
    "RandomTorque",
    "SimConfig",
    "SimResult",
    "SimulationDiverged",
    "Sensors",
    "StopCondition",
    "TorqueActuator",
    "simulate",
]
