"""Generic Floquet machinery for linear time-periodic descriptor systems.

    E(t) x'(t) = A(t) x(t),     E(t + T) = E(t),  A(t + T) = A(t),

with ``E(t)`` singular (algebraic variables, Lagrange multipliers, index up to 3).  See
``docs/floquet.md`` for the method, the Fast Floquet formula and the references.

Main entry points::

    dae = LinearPeriodicDAE(E, A, period, differential, S=None, blades=None)
    res = floquet_analysis(dae, method="radau", steps=None, ...)   # -> FloquetResult
    mono = monodromy(dae, method="radau", steps=None, ...)          # -> Monodromy

Methods
-------
``"radau"`` (default)
    3-stage Radau IIA (order 5 for ODEs / index 1; stiffly accurate, L-stable; convergent for
    index-3 Hessenberg systems, Hairer & Wanner II, sec. VI.7 and VII.4).
``"paper"``
    The paper's finite elements in time: central differencing (implicit midpoint, equal to the
    trapezoidal rule for constant coefficients) on the differential rows, algebraic rows
    collocated at the new node; second order, 1000 steps per period by default.

The algebraic and hidden-constraint components are removed by a state-space reduction on the
consistent subspace: a basis ``Z`` (n x d) of consistent initial values at t = 0 is obtained from
the range of three Radau IIA steps ending at t = 0 (stiffly accurate steps annihilate every
inconsistent component of an index <= 3 system); only these d columns are marched and the
monodromy is the d x d matrix ``Z_D^+ Phi(T) Z`` (D: differential rows).  The result therefore
contains exactly ``d`` = dim(consistent subspace) multipliers.
"""
from .analysis import FloquetResult, dominant_harmonic, floquet_analysis, periodic_modes
from .coefficients import DirectCoefficients, FourierCoefficients, LinearPeriodicDAE
from .monodromy import DEFAULT_STEPS, Monodromy, monodromy
from .steppers import RADAU_IIA

__all__ = ["LinearPeriodicDAE", "FourierCoefficients", "DirectCoefficients", "Monodromy",
           "FloquetResult", "monodromy", "floquet_analysis", "periodic_modes",
           "dominant_harmonic", "RADAU_IIA", "DEFAULT_STEPS"]
