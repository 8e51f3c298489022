"""Rigid-body subsystem (nacelle yaw, shaft, teetering hub) by Kane's method."""
from .kane import RigidSystem

__all__ = ["RigidSystem"]
