"""A cantilever wing in a uniform stream: one beam clamped at a root at rest, with strip-theory
unsteady aerodynamics at its Gauss points (the classic aeroelastic benchmarks, e.g. Goland's
wing), built from the same beam element (fem/beam.py) and airfoil model (aero/unsteady.py) as
the turbine.

Frames: the beam's root frame b is inertial: b1 along the span, b2 chordwise towards the
leading edge, b3 normal to the chord (b1 x b2). The air flows along -b2 at ``speed`` (the wing
flies along +b2). At each Gauss point, in its section frame B (turned with the section), the
air's velocity relative to the reference line (the elastic axis) is W = wind_B - V; the
section sees the chordwise speed U = -W2, the downwash at the three-quarter chord
w34 = W3 + b (1/2 - a) Omega1 (a: the reference line's position aft of mid-chord in
semi-chords), the plunge acceleration h'' = -(Vdot + Omega x V)3 (h positive down, as
Theodorsen's), the pitch rate Omega1 and acceleration Omegadot1. Theodorsen's lift acts along
B3 and his moment about B1, both at the reference line; Wagner's lag adds ``lag.states``
differential unknowns per Gauss point after the beam's unknowns.

Unknowns: ``[beam (12 + 18 N) | lag states (N, G, states)]``; residual rows likewise (the lag
rows are ``x' - rates``). All arithmetic complex-safe.
"""
from __future__ import annotations

import numpy as np

from ..aero.unsteady import JONES, IndicialLag, thin_airfoil_loads
from ..fem.discretization import beam_elements
from ..model import Beam, Wing
from ..numerics.rotations import cross

__all__ = ["WingModel"]


class WingModel:
    """``beam``: a model.Beam (its sections; b2 chordwise towards the leading edge);
    ``chord`` [m]; ``axis`` a (the reference line's position aft of mid-chord in semi-chords,
    -1 = leading edge); ``rho`` [kg/m^3]; ``lift_slope`` [1/rad]; ``lag``: IndicialLag
    (JONES, or QUASI_STEADY for C(k) = 1); ``elements`` (default the beam's)."""

    def __init__(self, beam: Beam, chord: float, axis: float, rho: float = 1.225,
                 lift_slope: float = 2.0 * np.pi, lag: IndicialLag = JONES,
                 elements=None, gauss: int = 3):
        if not chord > 0:
            raise ValueError(f"chord: {chord!r} is not allowed; need a number > 0 [m]")
        if not -1.0 <= axis <= 1.0:
            raise ValueError(f"axis: {axis!r} is not allowed; need a value from -1 (leading "
                             "edge) to 1 (trailing edge) [semi-chords aft of mid-chord]")
        self.beam = beam_elements(beam, elements, gauss=gauss)
        self.semichord = 0.5 * float(chord)
        self.axis = float(axis)
        self.rho = float(rho)
        self.lift_slope = float(lift_slope)
        self.lag = lag
        N, G, k = self.beam.N, len(self.beam.eta), lag.states
        self.aero_shape = (N, G, k)
        self.n_beam = self.beam.n
        self.n = self.n_beam + N * G * k
        self.differential = np.concatenate([self.beam.differential, np.ones(N * G * k, bool)])

    @classmethod
    def from_wing(cls, wing: Wing, elements=None, lag: IndicialLag = JONES) -> "WingModel":
        """The model of a model.Wing case."""
        return cls(wing.beam, wing.chord, wing.axis_semichords, rho=wing.density,
                   lift_slope=wing.lift_slope, lag=lag, elements=elements)

    def residual(self, yd, y, speed: float):
        """R (B, n) for (B, n) arrays (or (n,) for one state) in a stream of ``speed`` [m/s]."""
        one = np.ndim(y) == 1
        yd, y = np.atleast_2d(yd), np.atleast_2d(y)
        B = y.shape[0]
        N, G, k = self.aero_shape
        nb = self.n_beam
        x = y[:, nb:].reshape(B, N, G, k).transpose(1, 2, 0, 3)      # (N, G, B, k)
        b, a = self.semichord, self.axis
        lag_rows = {}

        def loads(sec):
            W = sec["wind"] - sec["V"]
            U = -W[..., 1]
            Om = sec["Omega"]
            w34 = W[..., 2] + b * (0.5 - a) * Om[..., 0]
            acc = sec["Vdot"] + cross(Om, sec["V"])
            w_eff = self.lag.effective_downwash(x, w34, U, b)
            lift, moment = thin_airfoil_loads(self.rho, U, b, a, -acc[..., 2], Om[..., 0],
                                              sec["Omegadot"][..., 0], w_eff,
                                              self.lift_slope)
            lag_rows["rates"] = self.lag.rates(x, w34, U, b)
            force = np.zeros(W.shape, dtype=W.dtype)
            force[..., 2] = lift
            torque = np.zeros(W.shape, dtype=W.dtype)
            torque[..., 0] = moment
            return force, torque

        zero = np.zeros((B, 3))
        wind = np.zeros((B, 3))
        wind[:, 1] = -float(speed)
        r_beam = self.beam.residual(yd[:, :nb], y[:, :nb], zero, zero, wind=wind,
                                    section_loads=loads)
        xd = yd[:, nb:].reshape(B, N, G, k).transpose(1, 2, 0, 3)
        r_lag = (xd - lag_rows["rates"]).transpose(2, 0, 1, 3).reshape(B, -1)
        out = np.concatenate([r_beam, r_lag], axis=1)
        return out[0] if one else out

    def linearization(self, speed: float):
        """(E, J) = (dR/dyd, dR/dy) at rest in the stream (the undeformed wing at zero
        incidence is the equilibrium), exact by complex step (all columns in one batch)."""
        n = self.n
        h = 1e-30
        eye = 1j * h * np.eye(n)
        zero = np.zeros((n, n), complex)
        E = self.residual(eye, zero, speed).imag.T / h
        J = self.residual(zero, eye, speed).imag.T / h
        return E, J

    def eigenvalues(self, speed: float):
        """The finite eigenvalues [1/s] of the linearized wing at ``speed``."""
        import scipy.linalg as sl
        E, J = self.linearization(speed)
        lam = sl.eigvals(-J, E)
        return lam[np.isfinite(lam) & (np.abs(lam) < 1e7)]
