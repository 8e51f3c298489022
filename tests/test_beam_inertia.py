"""The beam's inertial and gravity loads against rigid-body mechanics written in the test.

A very stiff blade moves as a rigid body with a steady root motion (root velocity ``v`` and
angular velocity ``w``, constant in the root frame b: the root runs on a circle, a helix or
stands still) in a gravity field ``g`` held in b.  Every material point then has the
acceleration

    a(s) = w x v + w x (w x s)          (s: position from the root point, in b)

and the loads the beam exerts on its root (``F0, M0``, the root unknowns) are minus the
loads needed to give its mass that acceleration against gravity:

    F0 = -int [m (a0 - g) + w x (w x (m x e1 + m xi))] dx,
    M0 = -int (m x e1 + m xi) x (a0 - g) dx - w x (J_root w),

with a0 = w x v, ``m xi`` the first moment of the section's mass about the reference line
(xi the mass-centre offset) and J_root the blade's inertia tensor about the root point (per
section i_ref + m x^2 (1 - e1 e1^T) + x (2 (e1 . m xi) 1 - e1 m xi^T - m xi e1^T)).  The
section table's 6x6 mass matrices (fem/sections.py station_mass, tested against its
definition) are linear between stations (docs/turbine-format.md), and so are these
integrands' coefficients: the test integrates them on each station interval by its own
Gauss rule, exactly.

Why these tests exist:
* with a mass-centre offset, the beam's V x P term (P = m (V + Omega x xi)) and the gravity
  moment m xi x g are the only terms that carry the offset's share of the root moment
  (tests/test_blade_modes.py checks them for a uniform blade spinning about the shaft and
  at rest; here: any steady root motion, a skew axis, pitch, a mass table varying along the
  span, the whole inertia tensor).  Probed: either term's sign flipped, or either scaled by
  1.01, fails the cases that exercise it (V x P: 'spin', 'rotor'; gravity: 'gravity',
  'rotor').
* a blade's mass falls steeply along the span, and the elements carry each element's
  average mass matrix: the weight is then exact on any mesh, the moments of the mass
  (gravity moment, centrifugal loads) converge at second order, as the mixed elements'
  frequencies do (docs/VALIDATION.md).
"""
from __future__ import annotations

import numpy as np
import pytest

from hawt_core.fem.beam import BeamElements
from hawt_core.fem.sections import mesh_beam, station_mass
from hawt_core.model import Beam, SectionTable
from hawt_core.numerics.jacobian import ColouredJacobian, block_tridiagonal_pattern
from hawt_core.numerics.newton import newton

LENGTH = 12.0          # m
STIFF = 1e13           # N m^2 and N: the blade is rigid for all practical purposes
#: a blade-like table: mass falling 50 x from root to tip, offsets and inertias varying
STATIONS = np.array([0.0, 0.06, 0.23, 0.55, 0.8, 1.0])
MASS = np.array([700.0, 420.0, 390.0, 210.0, 90.0, 14.0])                  # kg/m
CG = np.array([[0.0, 0.0], [0.35, -0.12], [0.5, 0.1], [0.2, 0.15], [0.1, 0.0],
               [0.05, -0.02]])                                              # (x2, x3) m
I_CG = np.array([[60.0, 40.0, 20.0], [30.0, 21.0, 9.0], [22.0, 16.0, 6.0],
                 [8.0, 6.0, 2.0], [2.0, 1.5, 0.5], [0.2, 0.15, 0.05]])      # kg m


def section_table(offset: bool = True) -> SectionTable:
    ns = len(STATIONS)
    stiff = np.full(ns, STIFF)
    return SectionTable(stations=STATIONS, mass=MASS, i1=I_CG[:, 0], i2=I_CG[:, 1],
                        i3=I_CG[:, 2], gj=stiff, ei2=stiff, ei3=stiff, ea=stiff,
                        ga2=stiff, ga3=stiff, cg_offset=CG if offset else np.zeros((ns, 2)))


def stiff_beam(elements: int, pitch: float) -> BeamElements:
    return BeamElements(mesh_beam(Beam(length=LENGTH, sections=section_table()), elements,
                                  pitch=pitch))


def steady_root_loads(beam: BeamElements, v, w, g):
    """Root loads (F0, M0) [N, N m] of the beam's steady state under the root motion."""
    z = np.zeros((1, beam.n))
    gg = None if g is None else np.asarray(g, float)[None]
    fun = lambda y: beam.residual(z, y[None], v[None], w[None], g=gg)[0]
    jac = ColouredJacobian(block_tridiagonal_pattern(beam.pattern_blocks()))
    y, _ = newton(fun, lambda y: jac(fun, y), beam.rigid_body_state(v, w), tol=1e-13,
                  what="stiff beam")
    return y[0:3], y[3:6]


def rigid_body_root_loads(pitch: float, v, w, g, offset: bool = True):
    """The closed form of the module docstring, the station matrices turned by the pitch
    about b1 and interpolated linearly, integrated by 4-point Gauss-Legendre on each
    station interval (the integrands are cubic in x there: exact)."""
    c, s = np.cos(pitch), np.sin(pitch)
    P = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
    mu = station_mass(section_table(offset))                       # (ns, 6, 6)
    m = mu[:, 0, 0]
    m_xi = np.einsum("ij,nj->ni", P, np.stack([mu[:, 5, 1], mu[:, 3, 2], mu[:, 4, 0]], -1))
    i_ref = P @ mu[:, 3:, 3:] @ P.T
    e1, one = np.array([1.0, 0.0, 0.0]), np.eye(3)
    g = np.zeros(3) if g is None else np.asarray(g, float)
    a0 = np.cross(w, v)
    F, M, J = np.zeros(3), np.zeros(3), np.zeros((3, 3))
    xg, wg = np.polynomial.legendre.leggauss(4)
    st = STATIONS * LENGTH
    for k in range(len(st) - 1):
        lo, hi = st[k], st[k + 1]
        for xq, wq in zip(0.5 * (hi - lo) * (xg + 1) + lo, 0.5 * (hi - lo) * wg):
            f = (xq - lo) / (hi - lo)
            mk = (1 - f) * m[k] + f * m[k + 1]
            mxk = (1 - f) * m_xi[k] + f * m_xi[k + 1]
            ik = (1 - f) * i_ref[k] + f * i_ref[k + 1]
            first = mk * xq * e1 + mxk                              # m c: mass x mass centre
            F -= wq * (mk * (a0 - g) + np.cross(w, np.cross(w, first)))
            M -= wq * np.cross(first, a0 - g)
            J += wq * (ik + mk * xq ** 2 * (one - np.outer(e1, e1))
                       + xq * (2 * (e1 @ mxk) * one - np.outer(e1, mxk) - np.outer(mxk, e1)))
    M -= np.cross(w, J @ w)
    return F, M


_W = 1.3 * np.array([0.25, -0.4, 0.88])            # rad/s, a general axis
CASES = {
    # a hanging or standing blade, gravity along every axis of b (gravity moment of xi)
    "gravity": (0.2, np.zeros(3), np.zeros(3), np.array([-3.0, 5.5, -7.4])),
    # a blade spinning about a skew axis, the root on a circle (V x P, Omega x H)
    "spin": (-0.35, np.cross(_W, [-1.5, 0.7, 0.2]), _W, None),
    # the paper's setting: the blade on a hub at radius 1.5 m spinning about the shaft b3
    # with 5 deg precone (w has a b1 part), gravity along the shaft (a carousel, physical)
    "rotor": (0.1, np.array([0.0, 1.5 * 2.0, 0.0]),
              2.0 * np.array([np.sin(0.087), 0.0, np.cos(0.087)]),
              -9.81 * np.array([np.sin(0.087), 0.0, np.cos(0.087)])),
}


@pytest.mark.parametrize("case", list(CASES))
def test_root_loads_of_a_rigid_blade_with_varying_mass_and_offset_mass_centre(case):
    """Reference: rigid-body mechanics (module docstring). Tolerances: at N = 16 and 32
    elements (nodes between the stations) the root loads converge at order 2 +- 0.1 (the
    element-average mass against the table's linear mass: observed 1.997-2.000), and
    their Richardson extrapolation (4 L32 - L16) / 3 is within 1e-5 of the closed form's
    scale (observed 5e-7 .. 2e-6; the blade's elastic deflection under stiffness 1e13
    contributes < 1e-7); a load the element averages integrate exactly (the weight) is
    exact at both meshes (1e-12)."""
    pitch, v, w, g = CASES[case]
    reference = rigid_body_root_loads(pitch, v, w, g)
    loads = [steady_root_loads(stiff_beam(N, pitch), v, w, g) for N in (16, 32)]
    for k, name in enumerate(("F0", "M0")):
        scale = np.linalg.norm(reference[k])
        e16, e32 = (np.linalg.norm(L[k] - reference[k]) / scale for L in loads)
        if e16 < 1e-12:
            assert e32 < 1e-12, (name, e16, e32)
            continue
        assert abs(np.log2(e16 / e32) - 2.0) < 0.1, (name, e16, e32)
        richardson = (4 * loads[1][k] - loads[0][k]) / 3
        assert np.linalg.norm(richardson - reference[k]) < 1e-5 * scale, (name, richardson,
                                                                          reference[k])


def test_the_offset_share_of_the_root_moment_is_large():
    """The cases above can fail for a sign error in the offset terms only if the offset's
    share of the root moment is large against their tolerance: moving the mass centre to
    the reference line changes M0 by > 1 % in each case (reference: the closed form)."""
    for case, (pitch, v, w, g) in CASES.items():
        _, M_offset = rigid_body_root_loads(pitch, v, w, g)
        _, M_centred = rigid_body_root_loads(pitch, v, w, g, offset=False)
        assert np.linalg.norm(M_offset - M_centred) > 1e-2 * np.linalg.norm(M_offset), case

