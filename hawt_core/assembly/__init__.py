"""The assembled models: the whole turbine (one residual R(ydot, y, t) for the rigid bodies,
the blades and the tower, with exact sparse Jacobians and its state layout) and one blade
clamped on the spinning hub."""
from .layout import BladeLayout, StateLayout
from .spinning_blade import SpinningBlade
from .turbine import TurbineModel

__all__ = ["BladeLayout", "StateLayout", "SpinningBlade", "TurbineModel"]
