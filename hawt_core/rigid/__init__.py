"""Rigid-body subsystem (nacelle yaw, shaft, teetering hub) by Kane's method, and its
actuators (pitch bearings, generator torque) as known functions of time."""
from .actuators import ControlInputs
from .kane import RigidSystem

__all__ = ["ControlInputs", "RigidSystem"]
