"""What real blades have beyond the straight uniform beam: a curved reference line (prebend,
sweep: fem/sections.py mesh_beam, reference_line, and the turned-frame elements of
fem/beam.py) and a rigid tip body (tip mass and inertia).

References, none an output of hawt: the straight beam (a line of zero curvature, and a
straight line inclined by the precone angle, must be the same physical blade); Castigliano's
closed-form tip deflections of a circular-arc cantilever (Euler-Bernoulli, in and out of
its plane; Roark's formulas for a quarter circle as a special case); the rigid-body
statics of a spinning and of a hanging arc with mass-centre offsets, integrated in the
test over the continuous arc; the frequency equations of a cantilever with a tip mass and
of a shaft with a tip disk.  Mesh studies: N = 16, 32, 64 and Richardson extrapolation
with the O(h^2) error of the polygon of straight elements.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad

from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.assembly import SpinningBlade
from hawt_core.fem.beam import BeamElements
from hawt_core.fem.sections import mesh_beam
from hawt_core.model import Beam, Hub, Nacelle, Rotor, SectionTable, Turbine
from hawt_core.numerics.jacobian import ColouredJacobian, block_tridiagonal_pattern
from hawt_core.numerics.newton import newton

M, L = 67.5772, 8.42
TABLE1 = dict(mass=M, i1=5.0, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6, ei3=21.8e6)
MESHES = (16, 32, 64)
DATA = Path(__file__).parent / "data"


def uniform(ns=2, **extra):
    st = np.linspace(0.0, 1.0, ns)
    return dict(stations=st, **{k: np.full(ns, v) for k, v in TABLE1.items()}, **extra)


def richardson2(f1, f2, f3):
    """Two-level Richardson extrapolation (h^2 + h^4) of values at h, h/2, h/4."""
    r1, r2 = (4 * f2 - f1) / 3, (4 * f3 - f2) / 3
    return (16 * r2 - r1) / 15


def arc_table(radius, angle, plane, ns=81, **extra):
    """Section table of a circular arc of ``radius`` [m] and ``angle`` [rad] leaving the root
    along b1 and bending towards +b3 ('prebend') or +b2 ('sweep'); the stations are span
    fractions along b1 (x1 = R sin(phi)), dense enough that the spline through them is
    exact to ~1e-9 of the radius."""
    phi = np.linspace(0.0, angle, ns)
    x1 = radius * np.sin(phi)
    offset = radius * (1 - np.cos(phi))
    d = uniform(ns, **extra)
    d["stations"] = x1 / x1[-1]
    d["prebend" if plane == "prebend" else "sweep"] = offset
    return SectionTable(**d), float(x1[-1])


def static_solve(beam, tip_force=None, tip_moment=None, g=None, v=None, w=None,
                 linear=False):
    """Steady state of one clamped beam (Newton, coloured complex-step Jacobian); ``linear``:
    the linear response about the undeformed rigid state (one Newton step)."""
    z = np.zeros((1, 3))
    v = z if v is None else np.atleast_2d(v)
    w = z if w is None else np.atleast_2d(w)
    tf = None if tip_force is None else np.atleast_2d(tip_force)
    tm = None if tip_moment is None else np.atleast_2d(tip_moment)
    g = None if g is None else np.atleast_2d(g)
    zero = np.zeros(beam.n)
    jac = ColouredJacobian(block_tridiagonal_pattern(beam.pattern_blocks()))
    f = lambda y: beam.residual(zero[None], y[None], v, w, g, tf, tm)[0]
    y0 = beam.rigid_body_state(v[0], w[0])
    if linear:
        from scipy.sparse.linalg import spsolve
        return y0 - spsolve(jac(f, y0).tocsc(), f(y0))
    y, _ = newton(f, lambda y: jac(f, y), beam.rigid_body_state(v[0], w[0]), tol=1e-13,
                  what="statics")
    return y


# ---------------------------------------------------------------------------- zero curvature
def test_zero_prebend_and_sweep_are_the_straight_beam():
    """Reference: the straight beam.  Prebend and sweep given as zeros at every station
    must give the same element matrices, the same residual (1e-14 relative, the turned
    frames are the identity) and the same blade modes (1e-10)."""
    rng = np.random.default_rng(3)
    base = uniform(5, twist=np.linspace(0.2, -0.1, 5),
                   cg_offset=np.tile([0.05, -0.02], (5, 1)))
    straight = Beam(L, SectionTable(**base), 6)
    zeros = Beam(L, SectionTable(**base, prebend=np.zeros(5), sweep=np.zeros(5)), 6)
    a, b = BeamElements(mesh_beam(straight)), BeamElements(mesh_beam(zeros))
    y, yd = rng.normal(size=(2, 1, a.n)) * 0.2
    v, w, g = rng.normal(size=(3, 1, 3))
    ra, rb = a.residual(yd, y, v, w, g), b.residual(yd, y, v, w, g)
    assert np.abs(ra - rb).max() <= 1e-14 * np.abs(ra).max()
    T = lambda beam: Turbine("t", Rotor(speed=6.02), Hub(), Nacelle(), beam)
    fa = blade_modes(T(straight), 8).frequencies()
    fb = blade_modes(T(zeros), 8).frequencies()
    np.testing.assert_allclose(fb, fa, rtol=1e-10)


@pytest.mark.parametrize("beta", [0.08, -0.15])
def test_an_inclined_straight_line_is_a_coned_blade(beta):
    """Reference: a straight blade with precone beta (root frame turned by -beta about b2,
    rigid/kane.py: b1 tilts towards +b3).  The same blade described with no precone and a
    linear prebend x3 = x1 tan(beta) (length
    L cos(beta) along b1) is the same body in the same motion: a line of zero curvature whose
    elements are all turned by beta.  The spinning blade's frequencies (centrifugal
    stiffening, Coriolis coupling, rotary inertia, mass-centre offsets all involved) agree
    to 1e-7 relative (eigen-solver round-off ~1e-10, 2e-8 at the top of the spectrum, 8000
    rad/s; a wrong element frame, a position off
    the line or an unturned mass matrix move them by 1e-3 or more)."""
    ns = 4
    extra = dict(twist=np.array([0.3, 0.2, 0.0, -0.1]),
                 cg_offset=np.tile([0.06, 0.02], (ns, 1)),
                 tension_offset=np.tile([0.03, -0.01], (ns, 1)),
                 ea=np.full(ns, 4e9), ga2=np.full(ns, 1e9), ga3=np.full(ns, 8e8))
    coned = Turbine("coned", Rotor(speed=6.02, precone=beta), Hub(), Nacelle(),
                    Beam(L, SectionTable(**uniform(ns, **extra)), 8))
    stations = np.linspace(0.0, 1.0, ns)
    span = L * np.cos(beta)
    bent = Turbine("bent", Rotor(speed=6.02), Hub(), Nacelle(),
                   Beam(span, SectionTable(**uniform(ns, **extra),
                                           prebend=stations * span * np.tan(beta)), 8))
    ra, rb = blade_modes(coned, 8), blade_modes(bent, 8)
    np.testing.assert_allclose(rb.frequencies(), ra.frequencies(), rtol=1e-7)
    assert [m.family for m in rb.modes] == [m.family for m in ra.modes]
    # and it is not the unconed straight blade
    flat = Turbine("flat", Rotor(speed=6.02), Hub(), Nacelle(),
                   Beam(L, SectionTable(**uniform(ns, **extra)), 8))
    assert np.abs(blade_modes(flat, 8).frequencies()[0] / ra.frequencies()[0] - 1) > 1e-4


# ---------------------------------------------------------------------------- statics of an arc
ARC_R, ARC_ANGLE, P = 6.0, np.pi / 3, 50.0


def _castigliano(plane, load):
    """Tip deflection along the load of a circular-arc cantilever (radius R, angle a,
    clamped at phi = 0, tangent b1 there), Euler-Bernoulli, inextensible, shear-rigid.
    Bending moment at phi from a tip force P:
      out of plane:   M = P R sin(a - phi) (bending about the in-plane normal) and
                      T = P R (1 - cos(a - phi)) (torsion)
      in plane, P along the root normal n: M = P R (sin a - sin phi) about the plane normal
      in plane, P along the root tangent b1: M = P R (cos phi - cos a)
    delta = dU/dP = P R^3 int (M^2/EI + T^2/GJ) / (P R)^2 dphi (quadrature to 1e-12).
    For a = pi/2, out of plane: P R^3 (pi/(4 EI) + (3 pi/4 - 2)/GJ) (Roark)."""
    a = ARC_ANGLE
    # EI about the plane's normal is the one in the plane of the arc
    ei_in = TABLE1["ei2"] if plane == "prebend" else TABLE1["ei3"]
    ei_out = TABLE1["ei3"] if plane == "prebend" else TABLE1["ei2"]
    if load == "out":
        b = quad(lambda p: np.sin(a - p) ** 2, 0, a, epsabs=1e-14)[0] / ei_out
        t = quad(lambda p: (1 - np.cos(a - p)) ** 2, 0, a, epsabs=1e-14)[0] / TABLE1["gj"]
        return P * ARC_R ** 3 * (b + t)
    arm = (lambda p: np.sin(a) - np.sin(p)) if load == "normal" else \
        (lambda p: np.cos(p) - np.cos(a))
    return P * ARC_R ** 3 * quad(lambda p: arm(p) ** 2, 0, a, epsabs=1e-14)[0] / ei_in


@pytest.mark.parametrize("plane", ["prebend", "sweep"])
@pytest.mark.parametrize("load", ["out", "normal", "tangent"])
def test_circular_arc_cantilever_tip_deflection_castigliano(plane, load):
    """Reference: _castigliano (closed form).  A 60-degree arc of radius 6 m with Table 1
    sections (EI2 != EI3, so the plane of the arc matters), rigid in extension and shear;
    the linear response to a tip force P = 50 N (one Newton step from the unloaded arc).  The N = 16, 32, 64
    tip deflections converge at second order (order 2 +- 0.3; observed 1.997-1.999) and
    their Richardson extrapolation is within 1e-7 of the closed form (observed 1.6e-9)."""
    table, span = arc_table(ARC_R, ARC_ANGLE, plane)
    normal = np.array([0.0, 0.0, 1.0]) if plane == "prebend" else np.array([0.0, 1.0, 0.0])
    out = np.array([0.0, 1.0, 0.0]) if plane == "prebend" else np.array([0.0, 0.0, 1.0])
    direction = {"out": out, "normal": normal, "tangent": np.array([1.0, 0.0, 0.0])}[load]
    tips = []
    for N in MESHES:
        beam = BeamElements(mesh_beam(Beam(span, table, N)))
        y = static_solve(beam, tip_force=P * direction, linear=True)
        tips.append(float(y[-18 + 6:-18 + 9] @ direction))
    tips = np.array(tips)
    exact = _castigliano(plane, load)
    e = np.abs(tips / exact - 1)
    order = np.log2(e[:-1] / e[1:])
    assert np.all(np.abs(order - 2) < 0.3), (order, e)
    assert abs(richardson2(*tips) / exact - 1) < 1e-7, (richardson2(*tips) / exact - 1)


def _arc_frame(phi, plane):
    """Section frame (a1 tangent, a2, a3) of the arc at phi in b, independent of hawt: the
    root frame turned about the arc's binormal by phi."""
    c, s = np.cos(phi), np.sin(phi)
    if plane == "prebend":          # turned about b2: a1 = (c, 0, s), a3 = (-s, 0, c)
        return np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])     # about b3


@pytest.mark.parametrize("plane", ["prebend", "sweep"])
def test_root_loads_of_a_spinning_and_a_hanging_arc(plane):
    """Reference: rigid-body statics of the continuous arc, integrated in the test.  A stiff
    arc (Table 1 stiffness x 1e5, 60 degrees, radius 6 m) with a mass-centre offset
    (x2, x3) = (0.1, -0.06) in its section frame and the sections' rotary inertia
    (i2, i3 = 1, 4 kg m), root at the origin of b:
    - spinning at w = (0.7, -0.4, 1.1) rad/s (about an axis through the root): each piece
      of arc m ds at p = r + A xi needs m w x (w x p) ds; the blade exerts on its clamp
      F0 = -int m w x (w x p) ds and M0 = -w x H, H = int (p x m (w x p) + A I A^T w) ds;
    - at rest under gravity g = (-3, 4, -8.5) m/s^2: F0 = int m g ds, M0 = int p x m g ds.
    Richardson extrapolation of N = 16, 32, 64 within 1e-6 of the largest component
    (the stiff arc's deflection moves the arms by ~1e-7); the V x P, Omega x H and gravity
    moment terms of the turned elements are all needed (the offset part of M0 is ~5 %)."""
    xi = np.array([0.0, 0.1, -0.06])
    i_sec = np.diag([5.0, 1.0, 4.0])
    stiff = {k: TABLE1[k] * 1e5 for k in ("gj", "ei2", "ei3")}
    a = ARC_ANGLE
    w = np.array([0.7, -0.4, 1.1])
    g = np.array([-3.0, 4.0, -8.5])

    def point(phi):
        r = ARC_R * (np.array([np.sin(phi), 0, 1 - np.cos(phi)]) if plane == "prebend"
                     else np.array([np.sin(phi), 1 - np.cos(phi), 0]))
        A = _arc_frame(phi, plane)
        return r + A @ xi, A

    def integral(fun):
        return np.array([quad(lambda p: fun(p)[k] * ARC_R, 0, a, epsabs=1e-12)[0]
                         for k in range(3)])

    def spin_H(phi):
        p, A = point(phi)
        return M * np.cross(p, np.cross(w, p)) + A @ i_sec @ A.T @ w

    F_spin = -integral(lambda phi: M * np.cross(w, np.cross(w, point(phi)[0])))
    M_spin = -np.cross(w, integral(spin_H))
    F_grav = M * ARC_R * a * g
    M_grav = integral(lambda phi: M * np.cross(point(phi)[0], g))

    loads = {"spin": [], "gravity": []}
    for N in MESHES:
        table, span = arc_table(ARC_R, a, plane, **{})
        d = {k: getattr(table, k) for k in ("stations", "mass", "prebend", "sweep")}
        ns = len(d["stations"])
        table = SectionTable(**d, i1=np.full(ns, 5.0), i2=np.full(ns, 1.0),
                             i3=np.full(ns, 4.0), **{k: np.full(ns, v) for k, v in stiff.items()},
                             cg_offset=np.tile(xi[1:], (ns, 1)))
        beam = BeamElements(mesh_beam(Beam(span, table, N)))
        loads["spin"].append(static_solve(beam, w=w)[:6])
        loads["gravity"].append(static_solve(beam, g=g)[:6])
    for case, F_ref, M_ref in (("spin", F_spin, M_spin), ("gravity", F_grav, M_grav)):
        got = richardson2(*np.array(loads[case]))
        ref = np.concatenate([F_ref, M_ref])
        np.testing.assert_allclose(got[:3], F_ref, atol=1e-6 * np.abs(F_ref).max(),
                                   err_msg=case)
        np.testing.assert_allclose(got[3:], M_ref, atol=1e-6 * np.abs(M_ref).max(),
                                   err_msg=case)
        assert np.abs(ref).max() > 0


def test_prebent_blade_spins_with_its_own_geometry():
    """Reference: the rigid-body statics above, for the blade-modes model: a stiff prebent
    blade on a hub (radius 1.8 m) spinning at 6.02 rad/s: the root force's b1 component is
    m Omega^2 int (e + x1) ds over the arc (ds = R dphi; the prebend is along the shaft, so
    it does not change the radius of each piece).  Richardson extrapolation of N = 16, 32,
    64 within 1e-6 (at N = 32 alone the polygon inscribed in the arc is 2e-5 short)."""
    a, R = 0.5, 12.0
    table, span = arc_table(R, a, "prebend")
    d = {k: getattr(table, k) for k in ("stations", "mass", "i1", "i2", "i3", "prebend")}
    ns = len(d["stations"])
    table = SectionTable(**d, **{k: np.full(ns, TABLE1[k] * 1e5) for k in ("gj", "ei2", "ei3")})
    T = Turbine("bent", Rotor(speed=6.02), Hub(radius=1.8), Nacelle(), Beam(span, table, 32))
    f1 = np.array([SpinningBlade(T, N).steady_state()[0] for N in MESHES])
    ref = M * 6.02 ** 2 * quad(lambda p: (1.8 + R * np.sin(p)) * R, 0, a)[0]
    assert abs(richardson2(*f1) / ref - 1) < 1e-6, richardson2(*f1) / ref - 1


# ---------------------------------------------------------------------------- the file format
def _turbine_dict():
    """A turbine with a flexible tower, as a plain dict to edit."""
    import yaml
    from hawt_core.io import dump_turbine, load_turbine
    return yaml.safe_load(dump_turbine(load_turbine(DATA / "three_blade_flexible_tower.yaml")))


def test_prebend_sweep_and_tip_body_round_trip_through_the_file():
    """Reference: the file format (docs/turbine-format.md): blade.sections.prebend and
    .sweep, one number per station [m], blade.tip_mass [kg] and blade.tip_inertia
    [kg m^2] are written and read back exactly."""
    from hawt_core.io import dump_turbine, turbine_from_dict, turbines_equal
    import yaml
    d = _turbine_dict()
    ns = len(d["blade"]["sections"]["stations"])
    st = np.array(d["blade"]["sections"]["stations"])
    d["blade"]["sections"]["prebend"] = (-0.3 * st ** 2).tolist()
    d["blade"]["sections"]["sweep"] = (0.05 * st ** 3).tolist()
    t = turbine_from_dict(d)
    assert t.blade.sections.prebend is not None and len(t.blade.sections.prebend) == ns
    back = turbine_from_dict(yaml.safe_load(dump_turbine(t)))
    assert turbines_equal(back, t)
    assert mesh_beam(back.blade).curved
    d["blade"]["tip_mass"] = 12.5
    d["blade"]["tip_inertia"] = [0.5, 1.5, 2.0]
    t = turbine_from_dict(d)
    assert t.blade.tip_mass == 12.5 and t.blade.tip_inertia == (0.5, 1.5, 2.0)
    assert turbines_equal(turbine_from_dict(yaml.safe_load(dump_turbine(t))), t)


@pytest.mark.parametrize("where,value,words", [
    ("blade", "root", ["blade.sections.prebend[0]", "must be 0"]),
    ("blade", "nan", ["blade.sections.prebend[1]", "finite"]),
    ("blade", "short", ["blade.sections.prebend", "stations"]),
    ("tower", "ok", ["tower.sections.prebend", "straight"]),
    ("blade", "negative tip", ["blade.tip_mass", ">= 0"]),
    ("blade", "bad inertia", ["blade.tip_inertia", "kg m^2"]),
    ("tower", "tip", ["tower.tip_mass", "unknown"]),
])
def test_bad_prebend_or_tip_body_is_refused_naming_the_key(where, value, words):
    """Reference: the loader's contract: an error naming the key, the value and what is
    allowed (the root of the line is the blade root; the tower stays straight)."""
    from hawt_core.io import TurbineFileError, turbine_from_dict
    d = _turbine_dict()
    sec = d[where]["sections"]
    ns = len(sec["stations"])
    if "tip" in value or "inertia" in value:
        d[where].update({"negative tip": {"tip_mass": -1.0}, "tip": {"tip_mass": 1.0},
                         "bad inertia": {"tip_inertia": [1.0, 2.0]}}[value])
    else:
        sec["prebend"] = {"root": [0.1] * ns, "nan": [0.0, float("nan")] + [0.0] * (ns - 2),
                          "short": [0.0] * (ns + 1), "ok": [0.0] * ns}[value]
    with pytest.raises(TurbineFileError) as ex:
        turbine_from_dict(d)
    for w in words:
        assert w in str(ex.value), (w, str(ex.value))


# ---------------------------------------------------------------------------- a rigid tip body
def _tip_turbine(tip_mass=0.0, tip_inertia=(0.0, 0.0, 0.0), elements=16):
    sec = SectionTable.uniform(mass=M, i1=5.0, i2=1e-6, i3=1e-6, gj=TABLE1["gj"],
                               ei2=TABLE1["ei2"], ei3=TABLE1["ei3"])
    return Turbine("tip", Rotor(speed=0.0), Hub(radius=0.0), Nacelle(),
                   Beam(L, sec, elements, tip_mass=tip_mass, tip_inertia=tip_inertia))


@pytest.mark.parametrize("ratio", [0.5, 2.0])
def test_tip_mass_cantilever_frequency_equation(ratio):
    """Reference: the Euler-Bernoulli cantilever with a tip point mass M_t = ratio m L:
    1 + cos(bL) cosh(bL) + ratio bL (cos(bL) sinh(bL) - sin(bL) cosh(bL)) = 0, omega =
    (bL)^2 sqrt(EI/(m L^4)) (roots by brentq); and the torsion of a shaft with a tip disk
    J1 = ratio I1 L: (kL) tan(kL) = 1/ratio, omega = k sqrt(GJ/I1).  Rotary inertia of the
    sections 1e-6 kg m.  Richardson (N = 8, 16, 32) within 1e-5 for the first two flap
    and torsion frequencies; without the tip body they move by more than 10 %."""
    from scipy.optimize import brentq
    f = lambda b: 1 + np.cos(b) * np.cosh(b) + ratio * b * (np.cos(b) * np.sinh(b)
                                                             - np.sin(b) * np.cosh(b))
    grid = np.linspace(0.3, 9.0, 2000)
    roots = [brentq(f, a, b) for a, b in zip(grid[:-1], grid[1:]) if f(a) * f(b) < 0][:2]
    flap = np.array(roots) ** 2 * np.sqrt(TABLE1["ei2"] / (M * L ** 4))
    g = lambda k: k * np.tan(k) - 1 / ratio
    tors = np.array([brentq(g, j * np.pi + 1e-9, j * np.pi + np.pi / 2 - 1e-9)
                     for j in range(2)]) / L * np.sqrt(TABLE1["gj"] / 5.0)
    got = {"flap": [], "torsion": []}
    for N in (8, 16, 32):
        T = _tip_turbine(ratio * M * L, (ratio * 5.0 * L, 0.0, 0.0), N)
        res = blade_modes(T, N, count=12)
        for fam in got:
            got[fam].append([m.frequency_rad_s for m in res.modes if m.family == fam][:2])
    for fam, exact in (("flap", flap), ("torsion", tors)):
        rich = richardson2(*np.array(got[fam]))
        np.testing.assert_allclose(rich, exact, rtol=1e-5, err_msg=fam)
    bare = blade_modes(_tip_turbine(elements=16), 16, count=12)
    assert [m.frequency_rad_s for m in bare.modes if m.family == "flap"][0] > 1.1 * flap[0]


def test_tip_body_loads_under_gravity_and_spin():
    """Reference: rigid-body statics (stiff uniform blade, tip body m_t = 40 kg with
    inertia J = (3, 7, 11) kg m^2 at the tip, tension-free root at the origin):
    at rest under g: F0 = (m L + m_t) g, M0 = (m L L/2 + m_t L) e1 x g; spinning at w about
    the root: F0 = -(m_t w x (w x L e1) + int m w x (w x x e1) dx),
    M0 = -w x (H_blade + m_t L e1 x (w x L e1) + J w).  Tolerance 1e-6 of the largest
    component (the stiff blade's deflection)."""
    mt, J = 40.0, np.array([3.0, 7.0, 11.0])
    sec = SectionTable.uniform(mass=M, i1=2.0, i2=0.5, i3=1.5,
                               **{k: TABLE1[k] * 1e6 for k in ("gj", "ei2", "ei3")})
    beam = BeamElements(mesh_beam(Beam(L, sec, 8, tip_mass=mt, tip_inertia=tuple(J))))
    g = np.array([-3.0, 4.0, -8.5])
    e1 = np.array([1.0, 0, 0])
    y = static_solve(beam, g=g)
    F_ref = (M * L + mt) * g
    M_ref = np.cross((M * L * L / 2 + mt * L) * e1, g)
    np.testing.assert_allclose(y[:3], F_ref, atol=1e-6 * np.abs(F_ref).max())
    np.testing.assert_allclose(y[3:6], M_ref, atol=1e-6 * np.abs(M_ref).max())
    w = np.array([0.7, -0.4, 1.1])
    y = static_solve(beam, w=w)
    xs, ws = np.polynomial.legendre.leggauss(8)
    x = 0.5 * L * (xs + 1)
    pts = x[:, None] * e1
    F_ref = -(mt * np.cross(w, np.cross(w, L * e1))
              + 0.5 * L * np.sum(ws[:, None] * M * np.cross(w, np.cross(w, pts)), 0))
    H = (0.5 * L * np.sum(ws[:, None] * M * np.cross(pts, np.cross(w, pts)), 0)
         + L * np.diag([2.0, 0.5, 1.5]) @ w
         + mt * np.cross(L * e1, np.cross(w, L * e1)) + J * w)
    M_ref = -np.cross(w, H)
    np.testing.assert_allclose(y[:3], F_ref, atol=1e-6 * np.abs(F_ref).max())
    np.testing.assert_allclose(y[3:6], M_ref, atol=1e-6 * np.abs(M_ref).max())


# ---------------------------------------------------------------------------- collective pitch
def test_pitch_of_a_straight_blade_is_added_twist():
    """Reference: the section tables' own twist: pitching a straight blade by p (every
    section turned about b1) is the same blade as one whose structural twist is raised by
    p at every station and whose mass-centre offset (given in the untwisted frame b) is
    turned by p.  Spinning at 6.02 rad/s (centrifugal, Coriolis and the flap/lag
    orientation to the plane of rotation all matter), Table 1 sections: frequencies 1e-8
    relative (eigen-solver round-off: 4e-9 at 3000 rad/s); the pitch does move them
    (> 1e-3)."""
    base = uniform(4, twist=np.array([0.3, 0.2, 0.0, -0.1]),
                   cg_offset=np.tile([0.06, 0.02], (4, 1)))
    p = 0.35
    T = lambda sec, pitch: Turbine("p", Rotor(speed=6.02, pitch=pitch), Hub(), Nacelle(),
                                   Beam(L, SectionTable(**sec), 8))
    pitched = blade_modes(T(base, p), 8).frequencies()
    c, s_ = np.cos(p), np.sin(p)
    turned = base["cg_offset"] @ np.array([[c, s_], [-s_, c]])      # (x2, x3) turned by p
    twisted = blade_modes(T(dict(base, twist=base["twist"] + p, cg_offset=turned), 0.0),
                          8).frequencies()
    np.testing.assert_allclose(pitched, twisted, rtol=1e-8)
    assert np.abs(blade_modes(T(base, 0.0), 8).frequencies()[0] / pitched[0] - 1) > 1e-3


def test_pitch_turns_a_prebend_into_a_sweep():
    """Reference: the same body: a blade with prebend x3 = f(x1) pitched by 90 degrees
    (about b1, from b2 towards b3) is the unpitched blade with sweep x2 = -f(x1) and its
    sections turned by 90 degrees (twist + pi/2).  Frequencies of the spinning blade
    1e-8 relative."""
    ns = 9
    st = np.linspace(0, 1, ns)
    f = 0.3 * st ** 2
    base = uniform(ns, twist=np.full(ns, -0.2))
    T = lambda sec, pitch: Turbine("p", Rotor(speed=6.02, pitch=pitch), Hub(), Nacelle(),
                                   Beam(L, SectionTable(**sec), 8))
    a = blade_modes(T(dict(base, prebend=f), np.pi / 2), 8).frequencies()
    b = blade_modes(T(dict(base, sweep=-f, twist=base["twist"] + np.pi / 2), 0.0), 8)
    np.testing.assert_allclose(a, b.frequencies(), rtol=1e-8)


def test_mode_count_of_a_curved_pitched_blade_with_one_rigid_shear_direction():
    """Reference: the DOF count (2 per flexible section direction and element): a prebent,
    pitched blade whose GA3 alone is rigid (EA, GA2 flexible) has 10 N dynamic states; the
    turned compliance mixes the rigid direction with the flexible ones, the count must not."""
    ns = 5
    st = np.linspace(0, 1, ns)
    sec = SectionTable(**uniform(ns, ea=np.full(ns, 4e9), ga2=np.full(ns, 1e9),
                                 prebend=0.4 * st ** 2, sweep=-0.1 * st ** 3))
    T = Turbine("c", Rotor(speed=6.02, pitch=0.3), Hub(), Nacelle(), Beam(L, sec, 6))
    beam = BeamElements(mesh_beam(T.blade, pitch=T.rotor.pitch))
    assert beam.dynamic_dimension() == 10 * 6
    r = blade_modes(T, 6)                         # the deflated pencil agrees (its own count)
    assert len(r.frequencies()) == 5 * 6


# ---------------------------------------------------------------------------- shear centre
@pytest.mark.parametrize("xs", [(0.15, 0.0), (0.0, -0.1), (0.08, 0.05)])
def test_shear_centre_offset_twists_under_a_force_through_the_reference_line(xs):
    """Reference: beam statics (linear; St-Venant torsion about the shear centre): a
    cantilever whose shear centre sits at x_s = (x2s, x3s) from the reference line, loaded
    at the tip by a force (0, P2, P3) through the reference line: the force's moment about
    the shear centre, M1 = x3s P2 - x2s P3, twists it uniformly, tip twist
    phi = M1 L / GJ (exact for the element: constant torque); turning about the shear
    centre moves the reference line by phi e1 x (-x_s): the tip deflection differs from
    the same beam's without the offset by (x3s phi, -x2s phi) (the bending part, and its
    O(h^2) discretization error, cancel in the difference).  1e-9 relative."""
    P2, P3 = 40.0, -70.0
    tips = []
    for off in (xs, (0.0, 0.0)):
        sec = SectionTable(**uniform(2), shear_offset=np.tile(off, (2, 1)))
        beam = BeamElements(mesh_beam(Beam(L, sec, 4)))
        y = static_solve(beam, tip_force=np.array([0.0, P2, P3]), linear=True)
        tips.append((y[-18 + 6:-18 + 9], y[-18 + 9:-18 + 12]))
    (u, th), (u0, th0) = tips
    phi = (xs[1] * P2 - xs[0] * P3) * L / TABLE1["gj"]
    assert th[0] == pytest.approx(phi, rel=1e-9) and th0[0] == 0.0
    np.testing.assert_allclose(u[1:] - u0[1:], [xs[1] * phi, -xs[0] * phi], rtol=1e-9,
                               atol=1e-12)
