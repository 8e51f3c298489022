"""Solvers on the assembled models: the constant and the periodic (harmonic balance) steady
states, the time marching (initial state, implicit midpoint step and window solvers), and
the Floquet analyses of the linearization (monodromy with Fast Floquet, Hill's method,
multi-blade coordinates)."""
