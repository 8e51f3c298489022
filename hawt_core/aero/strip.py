"""Strip theory at a beam's Gauss points: the airfoil loads of sections in a relative wind.

Each Gauss point of a blade's beam carries an airfoil of chord ``c`` and aerodynamic twist
``tau`` (interpolated from the AeroDyn stations), in the element's section frame (which
carries the pitch and a curved line's turn) turned by the elastic rotation: the deformed
section frame B.  Given the air velocity relative to the section ``W`` in B components, in
B's chord plane (B2, B3):

    phi_B = atan2(W3, -W2),   alpha = phi_B + tau,   q = rho (W2^2 + W3^2) / 2

(hawt's twist sign: AeroDyn's -BlTwist); lift along (W3, -W2)/|W|, drag along W, the pitching
moment c_m q c^2 about B1, all at the aerodynamic centre: on the reference line, or (the
model's ``ac_chordwise`` = a) a distance a ahead of it along the chord, d = a (0, cos tau,
sin tau) in B, which adds the moment d x F of the force about the reference line (a HAWC2
blade's c2 line is the half chord, its aerodynamic centre the quarter chord).  The velocity
is the reference line's (the section's rotation rate times d is left out: the rotor's spin
moves d along the span, which carries no load; an unsteady airfoil model reads the
three-quarter chord's, :meth:`BladeStrips.three_quarter_chord`, and adds Theodorsen's
added-mass loads, :meth:`BladeStrips.added_mass_loads`); the spanwise component W1 carries no
load (independence principle).

The beam's section-load unknowns are in components of the root frame b turned by the elastic
rotation, not of B: :meth:`BladeStrips.to_section` and :meth:`BladeStrips.from_section` apply
the element frames.  Everything is complex-step safe.
"""
from __future__ import annotations

import numpy as np

from ..numerics.rotations import atan2
from .polars import StationPolars
from .unsteady import added_mass_loads

__all__ = ["BladeStrips", "inflow_sine"]


def inflow_sine(W, axis, motion):
    """|sin phi| of the inflow angle in the rotor frame, from the relative air velocity ``W``
    and the shaft axis ``axis`` and direction of the blade's motion ``motion`` (..., 3), the
    same components: phi = atan2(W . axis, -W . motion) (complex-step safe: the sign from the
    real part), for Prandtl's factors."""
    Wa = np.sum(W * axis, axis=-1)
    Wt = -np.sum(W * motion, axis=-1)
    return Wa * np.sign(np.real(Wa)) / np.sqrt(Wa * Wa + Wt * Wt)


class BladeStrips:
    """The airfoils at Gauss points ``span_fraction`` (N, G) (fractions of the blade length,
    0 at the root) of a blade with aerodynamic description ``aero`` (model.Aerodynamics),
    element section frames ``frames`` (N, 3, 3) in b, in air of density ``rho`` [kg/m^3]."""

    def __init__(self, aero, span_fraction: np.ndarray, frames: np.ndarray, rho: float):
        s = np.asarray(span_fraction, float)
        self.chord = np.interp(s, aero.stations, aero.chord)[:, :, None]        # (N, G, 1)
        self.tau = np.interp(s, aero.stations, aero.twist)[:, :, None]
        self.polars = StationPolars(aero, s.ravel())
        #: the aerodynamic centre from the reference line in B (N, G, 1, 3) [m] (in the
        #: chord plane: d1 = 0), or None
        self.ac_offset = None
        ahead = np.zeros_like(self.chord)
        if aero.ac_chordwise is not None:
            ahead = np.interp(s, aero.stations, aero.ac_chordwise)[:, :, None]
            self.ac_offset = np.stack([0 * ahead, ahead * np.cos(self.tau),
                                       ahead * np.sin(self.tau)], -1)
        #: the chord's normal in B (N, G, 1, 3): B1 x the chord towards the leading edge
        #: (lift's "up", a nose-up pitch turns the chord towards it)
        self.normal = np.stack([0 * self.tau, -np.sin(self.tau), np.cos(self.tau)], -1)
        #: the semi-chord b [m] and Theodorsen's a, the reference line aft of mid-chord in
        #: semi-chords (the aerodynamic centre is the quarter chord: a = ahead / b - 1/2)
        #: (N, G, 1)
        self.semichord = 0.5 * self.chord
        self.axis = ahead / self.semichord - 0.5
        self.frames = np.ascontiguousarray(np.asarray(frames, float)[:, None, None, :, :])
        self.rho = float(rho)

    def to_section(self, x):
        """Turned-b components (N, G, B, 3) -> section-frame B components."""
        return np.einsum("ngbji,ngbj->ngbi", self.frames, x)

    def from_section(self, x):
        """Section-frame B components (N, G, B, 3) -> turned-b components."""
        return np.einsum("ngbij,ngbj->ngbi", self.frames, x)

    def angle_of_attack(self, W):
        """(alpha [rad], chord-plane speed [m/s]) (N, G, B) of the relative air velocity
        ``W`` (N, G, B, 3) [m/s] in section-frame components."""
        W2, W3 = W[..., 1], W[..., 2]
        return atan2(W3, -W2) + self.tau, np.sqrt(W2 * W2 + W3 * W3)

    def three_quarter_chord(self, W, pitch_rate):
        """The air velocity relative to the three-quarter-chord point (N, G, B, 3) in B, from
        the reference line's ``W`` and the section's pitch rate [rad/s] (N, G, B) about B1:
        W + b (1/2 - a) pitch_rate n (the chord-plane part of W - Omega x d; the point lies
        b (1/2 - a) aft of the reference line)."""
        return W + (self.semichord * (0.5 - self.axis) * pitch_rate)[..., None] * self.normal

    def added_mass_loads(self, normal_rate, pitch_rate, pitch_acc, speed):
        """Theodorsen's non-circulatory force and moment per unit length (aero/unsteady.py's
        added_mass_loads) in section-frame components (N, G, B, 3), lift along the chord's
        normal, the moment about B1 at the reference line, from the rate of the air's
        velocity normal to the chord ``normal_rate`` [m/s^2], the pitch rate [rad/s] and
        acceleration [rad/s^2] and the chord-plane speed [m/s] (N, G, B)."""
        lift, pitching = added_mass_loads(self.rho, speed, self.semichord, self.axis,
                                          normal_rate, pitch_rate, pitch_acc)
        force = lift[..., None] * self.normal
        moment = np.zeros(force.shape, dtype=force.dtype)
        moment[..., 0] = pitching
        return force, moment

    def loads(self, W, alpha=None):
        """Force and moment per unit length [N/m, N m/m] (N, G, B, 3) in section-frame
        components from the relative air velocity ``W`` (N, G, B, 3) [m/s] in section-frame
        components, and a dict of the Gauss-point arrays (N, G, B): ``alpha`` [rad] (the
        angle the coefficients were read at), ``w`` (the chord-plane speed [m/s]), ``cl``,
        ``cd``.  ``alpha``: the angle of attack at which to read the polars (N, G, B), e.g.
        an unsteady-airfoil model's effective angle; default W's own (quasi-steady); lift
        stays normal to W, drag along it."""
        W2, W3 = W[..., 1], W[..., 2]
        w2 = W2 * W2 + W3 * W3
        w = np.sqrt(w2)
        if alpha is None:
            alpha = atan2(W3, -W2) + self.tau
        B = alpha.shape[2]
        cl, cd, cm = self.polars.coefficients(alpha.transpose(2, 0, 1).reshape(B, -1))
        cl, cd, cm = (c.reshape(B, *alpha.shape[:2]).transpose(1, 2, 0) for c in (cl, cd, cm))
        qc = 0.5 * self.rho * w2 * self.chord
        force = np.zeros(W.shape, dtype=np.result_type(W, alpha))
        force[..., 1] = qc * (cl * W3 + cd * W2) / w
        force[..., 2] = qc * (-cl * W2 + cd * W3) / w
        moment = np.zeros(W.shape, dtype=force.dtype)
        moment[..., 0] = qc * self.chord * cm
        if self.ac_offset is not None:
            # d x F: d and F both lie in the chord plane, so only about B1
            d = self.ac_offset
            moment[..., 0] += d[..., 1] * force[..., 2] - d[..., 2] * force[..., 1]
        return force, moment, {"alpha": alpha, "w": w, "cl": cl, "cd": cd}
