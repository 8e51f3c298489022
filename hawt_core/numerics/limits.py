"""The one set of limits on what hawt accepts: from a turbine file, the command line, a node
parameter or a service request (docs/turbine-format.md, "Limits", lists them).

They bound the work and memory a single input can ask for, so that a hostile or mistaken
input (a YAML alias bomb, a 50 MB file, 100000 elements, a rotor speed of 1e6 rad/s) is
refused in well under a second with a message naming the field and the limit, before any
large allocation, instead of running out of memory or into a diverging Newton iteration.
Each limit is far beyond any real turbine's need (the IEA 15-MW file is 0.9 MB with 56
polars of 200 angles; wind turbines turn below 10 rad/s).
"""
from __future__ import annotations

__all__ = ["MAX_FILE_BYTES", "MAX_YAML_DEPTH", "MAX_YAML_VALUES", "MAX_SCALAR_CHARS",
           "MAX_STATIONS", "MAX_ELEMENTS", "MAX_ORDER", "MAX_BLADES", "MAX_POLARS", "MAX_POLAR_ANGLES",
           "MAX_ROTOR_SPEED", "MAX_STEP_DEG", "MAX_PERTURB_ANGLE", "MAX_PERTURB_RATE",
           "LIMITS"]

#: Largest turbine file [bytes] (16 MiB; the shipped IEA 15-MW with its polars: 0.9 MB).
MAX_FILE_BYTES = 16 * 1024 * 1024
#: Deepest nesting of YAML collections (a turbine file needs 5: a 6x6 matrix per station).
MAX_YAML_DEPTH = 32
#: Most values (scalars, with every alias expanded) in one YAML file (2.4 times the IEA
#: 15-MW's 41452; PyYAML builds this many in about 0.6 s).
MAX_YAML_VALUES = 100_000
#: Longest single YAML value [characters] (a name, a number).
MAX_SCALAR_CHARS = 4096
#: Most spanwise stations of one table (sections, aerodynamic stations).
MAX_STATIONS = 1000
#: Most finite elements per blade or tower (for the p-version, elements x order: its cells).
MAX_ELEMENTS = 512
#: Highest polynomial degree of the p-version beam elements (fem/spectral.py); past ~8 the
#: cells' quadrature, not the degree, limits the accuracy.
MAX_ORDER = 12
#: Most blades of a rotor.
MAX_BLADES = 64
#: Most airfoil polars, and most angles of attack in one polar.
MAX_POLARS = 500
MAX_POLAR_ANGLES = 2000
#: Fastest rotor speed [rad/s] (955 rpm; a multi-megawatt rotor turns at about 1 rad/s).
MAX_ROTOR_SPEED = 100.0
#: Largest simulation time step [deg of rotor azimuth]: beyond it the blade's per-rev
#: motion is not resolved (36 steps per revolution).
MAX_STEP_DEG = 10.0
#: Largest initial perturbation of a rigid angle [rad] (yaw, teeter) and of its rate
#: [rad/s]: the linearization-scale motions a simulation is started from.
MAX_PERTURB_ANGLE = 1.0
MAX_PERTURB_RATE = 2.0

#: name -> (value, unit, what it bounds): the table docs/turbine-format.md reproduces.
LIMITS = {
    "MAX_FILE_BYTES": (MAX_FILE_BYTES, "bytes", "size of a turbine file"),
    "MAX_YAML_DEPTH": (MAX_YAML_DEPTH, "levels", "nesting of YAML lists and mappings"),
    "MAX_YAML_VALUES": (MAX_YAML_VALUES, "values", "values in a file, aliases expanded"),
    "MAX_SCALAR_CHARS": (MAX_SCALAR_CHARS, "characters", "one YAML value"),
    "MAX_STATIONS": (MAX_STATIONS, "stations", "one spanwise table"),
    "MAX_ELEMENTS": (MAX_ELEMENTS, "elements", "finite elements per blade or tower"),
    "MAX_ORDER": (MAX_ORDER, "degree", "polynomial degree of the beam elements"),
    "MAX_BLADES": (MAX_BLADES, "blades", "blades of a rotor"),
    "MAX_POLARS": (MAX_POLARS, "polars", "airfoil polars"),
    "MAX_POLAR_ANGLES": (MAX_POLAR_ANGLES, "angles", "angles of attack in one polar"),
    "MAX_ROTOR_SPEED": (MAX_ROTOR_SPEED, "rad/s", "rotor speed"),
    "MAX_STEP_DEG": (MAX_STEP_DEG, "deg", "simulation time step (rotor azimuth)"),
    "MAX_PERTURB_ANGLE": (MAX_PERTURB_ANGLE, "rad", "initial yaw or teeter perturbation"),
    "MAX_PERTURB_RATE": (MAX_PERTURB_RATE, "rad/s", "initial yaw or teeter rate"),
}
