"""Multi-blade coordinates (hawt_core/multiblade.py) and the Floquet analysis of rotors with
three or more blades.

References and tolerances (each test says which):
- an independent Coleman transform written here (dense, from TurbineModel.linearize at
  several times): the transformed matrices are constant for an isotropic rotor without
  gravity, and their finite eigenvalues (scipy.linalg.eig) are the fixed-frame exponents;
- the Floquet exponents of the rotating-frame monodromy (Radau IIA, Fast Floquet over T/Nb)
  equal those eigenvalues modulo whole per-rev (the same discretized equations, two routes);
- neutral stability: with no damping the fixed-frame mass matrix is SPD, the gyroscopic one
  skew and the stiffness PSD, so every exponent is imaginary;
- blade-count invariance: collective modes load the hub with a zero net force and moment, so
  they equal the single clamped blade (hawt_core.blade_modes).
"""
import dataclasses as dc

import numpy as np
import pytest
import scipy.linalg as sl

from hawt_core.assembly import TurbineModel
from hawt_core.solvers.steady import constant_steady_state
from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.io import load_turbine
from hawt_core.analyses.modal import modal_analysis
from hawt_core.solvers.multiblade import MultiBladeTransform, coordinate_names
from tower_turbines import tower_beam

PAPER = load_turbine()


def rigid_hub_rotor(blades, tower=False, **nacelle):
    """Table 1 blades at 360/Nb deg on a rigid, massless hub (inertias 1e-9), free yaw; with
    ``tower`` on the soft 25 m tower of tests/tower_turbines.py (hub 1000 kg, nacelle
    3000 kg)."""
    T = dc.replace(PAPER, rotor=dc.replace(PAPER.rotor, blades=blades),
                   hub=dc.replace(PAPER.hub, teeter=False, inertia_lateral=1e-9,
                                  inertia_longitudinal=1e-9),
                   nacelle=dc.replace(PAPER.nacelle, **nacelle))
    if tower:
        T = dc.replace(T, tower=tower_beam(25.0, 400.0, 6e8, 6e8, 1.5e9, 300.0, 4, False),
                       hub=dc.replace(T.hub, mass=1000.0),
                       nacelle=dc.replace(T.nacelle, mass=3000.0, inertia_pitch=2000.0,
                                          inertia_roll=1500.0))
    return T


CASES = [pytest.param(rigid_hub_rotor(3), id="3-blades-free-yaw"),
         pytest.param(rigid_hub_rotor(4, shaft_tilt=0.1), id="4-blades-free-yaw-tilt"),
         pytest.param(rigid_hub_rotor(5), id="5-blades-free-yaw"),
         pytest.param(rigid_hub_rotor(3, tower=True), id="3-blades-flexible-tower"),
         # the p-version (fem/spectral.py) on the blades and the tower: the same three routes
         pytest.param(dc.replace(rigid_hub_rotor(3, tower=True),
                                 blade=dc.replace(PAPER.blade, order=3),
                                 tower=dc.replace(tower_beam(25.0, 400.0, 6e8, 6e8, 1.5e9,
                                                             300.0, 2, False), order=3)),
                      id="3-blades-flexible-tower-order-3")]


def coleman(model, y, t):
    """Dense multi-blade transform written independently of hawt_core.multiblade:
    E_z = T^-1 E T, A_z = T^-1 (A T - E dT/dt), T(t) from cos/sin(k psi_b), (-1)^b."""
    nb, W = model.n_blades, model.rotor_speed
    E, A = (M.toarray() for M in model.linearize(y, t=t))
    psi = W * t + 2 * np.pi * np.arange(nb) / nb
    cols, dcols = [np.ones(nb)], [np.zeros(nb)]
    for k in range(1, (nb - 1) // 2 + 1):
        cols += [np.cos(k * psi), np.sin(k * psi)]
        dcols += [-k * W * np.sin(k * psi), k * W * np.cos(k * psi)]
    if nb % 2 == 0:
        cols.append((-1.0) ** np.arange(nb))
        dcols.append(np.zeros(nb))
    C, Cd = np.array(cols).T, np.array(dcols).T
    off, nbl = model.layout.blade_offset(0), model.beam.n
    Tm, Td = np.eye(model.n), np.zeros((model.n, model.n))
    blk = slice(off, off + nb * nbl)
    Tm[blk, blk] = np.kron(C, np.eye(nbl))
    Td[blk, blk] = np.kron(Cd, np.eye(nbl))
    Ti = np.linalg.inv(Tm)
    return Ti @ E @ Tm, Ti @ (A @ Tm - E @ Td)


def coleman_eigenvalues(model, y, band):
    """Finite eigenvalues of the constant Coleman-transformed pencil, Im >= 0, |eta| < band
    [per-rev]; and the largest relative change of the matrices over a revolution."""
    W = model.rotor_speed
    Ez, Az = coleman(model, y, 0.0)
    change = 0.0
    for t in (0.17, 0.61, 1.3):
        E1, A1 = coleman(model, y, t * model.period)
        change = max(change, np.abs(E1 - Ez).max() / np.abs(Ez).max(),
                     np.abs(A1 - Az).max() / np.abs(Az).max())
    al, be = sl.eig(Az, Ez, right=False, homogeneous_eigvals=True)
    fin = np.abs(be) > 1e-12 * np.abs(al)
    ev = al[fin] / be[fin] / W
    ev = ev[(np.abs(ev) < band) & (ev.imag >= -1e-9)]
    return ev, change


@pytest.mark.parametrize("turbine", CASES)
def test_floquet_equals_multiblade_eigenvalues(turbine):
    """Three routes to the exponents of the same discretized equations (N = 3):
    (1) the independent dense Coleman transform above: constant to 1e-11 over a revolution,
    its finite eigenvalues; (2) hawt's multi-blade path (method="hill": Hill's method with
    constant coefficients, one sparse eigenproblem); (3) the rotating-frame Floquet monodromy
    (Radau IIA, 400 steps, Fast Floquet over T/Nb).  Every exponent below 8 per-rev of (3)
    equals one of (1) modulo whole per-rev, and (2)'s fixed-frame exponents equal (1), to
    1e-8 relative (the free yaw angle's defective double zero, sensitive as sqrt(eps): 1e-6
    absolute); all three find the same number of modes."""
    model = TurbineModel(turbine, elements=3)
    y = constant_steady_state(model)
    ref, change = coleman_eigenvalues(model, y, 9.0)
    assert change < 1e-11             # round-off (paper's element ~1e-13, order 3 ~6e-12)
    mbc = modal_analysis(turbine, elements=3, method="hill", max_per_rev=9.0)
    flo = modal_analysis(turbine, elements=3, method="radau", steps=400)
    assert mbc.settings["frame"] == "multi-blade"
    # constant coefficients: no harmonic kept (order 3: the round-off variation above, 6e-12
    # of the largest entry, is above the Fourier trim's 1e-12, so one harmonic is kept;
    # the exponents below are the same)
    assert mbc.settings["hill_harmonics"] <= (0 if turbine.blade.order == 1 else 1)
    assert flo.settings["fast"]

    # the monodromy of the p-version (order 3) carries the round-off of its stiffer spectrum
    # (test_undamped_rotor_is_neutrally_stable): 1e-7 there (observed 1.05e-8)
    marching_tol = 1e-8 if turbine.blade.order == 1 else 1e-7

    def check(eta, shift_allowed):
        d = ref - eta
        if shift_allowed:
            d = d - 1j * np.round(d.imag)
        j = int(np.argmin(np.abs(d)))
        zero = abs(ref[j]) < 1e-6
        err = abs(d[j]) if zero else abs(d[j]) / abs(ref[j])
        assert err < (1e-6 if zero else marching_tol if shift_allowed else 1e-8), \
            (eta, ref[j], err)
        return err
    worst = 0.0
    for m in mbc.modes:
        if m.fixed_frame_per_rev < 8:
            worst = max(worst, check(complex(m.real_per_rev, m.fixed_frame_per_rev), False))
    for m in flo.modes:
        if m.fixed_frame_per_rev < 8:
            worst = max(worst, check(complex(m.real_per_rev, m.frequency_per_rev), True))
    # the yaw angle's double zero: two real exponents, or an O(sqrt(eps)) complex pair
    count = lambda r: sum(m.fixed_frame_per_rev < 8 for m in r.modes if m.family != "yaw")
    assert count(mbc) == count(flo) == int(np.sum(np.abs(ref) < 8) - np.sum(np.abs(ref) < 1e-6))
    for r in (mbc, flo):
        assert all(abs(complex(m.real_per_rev, m.frequency_per_rev)) < 1e-6
                   for m in r.modes if m.family == "yaw")
    print(f"{turbine.rotor.blades} blades: {count(mbc)} modes below 8/rev, worst relative "
          f"difference {worst:.1e}")


@pytest.mark.parametrize("turbine", CASES)
def test_undamped_rotor_is_neutrally_stable(turbine):
    """No structural damping: every exponent below 8 per-rev is imaginary to 1e-8 per-rev
    (the fixed-frame equations are those of an SPD mass, a skew gyroscopic and a PSD
    stiffness matrix), in the multi-blade eigenproblem and in the Floquet monodromy (Radau
    IIA with 800 steps: its numerical dissipation at 8 per-rev is ~1e-10 per-rev there,
    ~1e-8 with 400; with the p-version 3e-6, round-off, see below).  The free yaw angle's defective double zero splits by O(sqrt(eps)) in
    the marching: |eta| < 1e-6 per-rev there."""
    for method in ("hill", "radau"):
        r = modal_analysis(turbine, elements=3, method=method, max_per_rev=9.0, steps=800
                           if method == "radau" else None)
        worst = max(abs(m.real_per_rev) for m in r.modes
                    if m.fixed_frame_per_rev < 8 and m.family != "yaw")
        # the p-version's monodromy (order 3): 5.4e-7 at 800 steps and 1.5e-6 at 1600, i.e.
        # round-off accumulated over the steps (its stiffer spectrum), not the method's
        # dissipation (which falls with the steps); Hill's method stays at 1e-12 there
        tol = 1e-8 if method == "hill" or turbine.blade.order == 1 else 3e-6
        assert worst < tol, (method, worst)
        assert all(abs(complex(m.real_per_rev, m.frequency_per_rev)) < 1e-6
                   for m in r.modes if m.family == "yaw")


@pytest.mark.parametrize("blades,precone", [(2, 0.0), (3, 0.0), (4, 0.0), (5, 0.0),
                                            (3, 0.15), (4, 0.3)])
def test_collective_modes_equal_the_single_clamped_blade(blades, precone):
    """Blade-count invariance: with 2..5 identical blades on a rigid hub with free yaw, every
    collective (symmetric for two blades) flap, lag and torsion mode below 20 per-rev equals
    the single clamped blade's (hawt_core.blade_modes, dense eigen-analysis) to 1e-7
    relative (2 blades: the Radau IIA marching error, 1e-6).  With precone (0.15 and 0.3
    rad) too: the clamped blade then spins about the shaft, not its own flap axis, and the
    whole turbine's collective modes (root motion through Kane's kinematics) agree."""
    T = rigid_hub_rotor(blades)
    T = dc.replace(T, rotor=dc.replace(T.rotor, precone=precone))
    r = modal_analysis(T, elements=4, max_per_rev=20)
    single = blade_modes(T, 4)
    sym = "symmetric" if blades == 2 else "collective"
    tol = 1e-6 if blades == 2 else 1e-7
    checked = 0
    for fam in ("flap", "lag", "torsion"):
        ref = [m.frequency_per_rev for m in single.modes if m.family == fam
               and m.frequency_per_rev < 19]
        got = [m.frequency_per_rev for m in r.modes if m.family == fam and m.symmetry == sym]
        assert len(got) >= len(ref), (fam, got, ref)
        np.testing.assert_allclose(got[:len(ref)], ref, rtol=tol)
        checked += len(ref)
    assert checked >= 7


def test_whirl_labels_and_fixed_frame_frequencies():
    """Three blades, free yaw: the fixed-frame frequency of a cyclic mode is the rotating one
    plus 1 per-rev for forward whirl and minus 1 per-rev for backward whirl (an isotropic
    rotor's cyclic mode is a single harmonic in the rotating frame: exact to 1e-9), collective
    modes have equal frequencies in both frames; the labels read "1st backward-whirl flap"
    etc.; the JSON carries the fixed-frame fields; the table prints fixed-frame values."""
    r = modal_analysis(rigid_hub_rotor(3), elements=4, max_per_rev=12)
    seen = set()
    for m in r.modes:
        if m.family in ("yaw",):
            continue
        shift = {"collective": 0, "forward": 1, "backward": -1}[m.whirl]
        assert m.fixed_frame_per_rev == pytest.approx(m.frequency_per_rev + shift, abs=1e-9)
        assert m.symmetry == {"collective": "collective", "forward": "forward-whirl",
                              "backward": "backward-whirl"}[m.whirl]
        seen.add(m.whirl)
    assert seen == {"collective", "forward", "backward"}
    assert r.find("flap", "backward-whirl", 1).fixed_frame_per_rev == pytest.approx(
        r.find("flap", "collective", 1).frequency_per_rev + 0.0, rel=0.2)
    d = r.to_dict()["modes"][3]
    assert {"fixed_frame_per_rev", "fixed_frame_hz", "whirl"} <= set(d)
    table = r.table()
    assert "fixed-frame eigenvalue" in table and "1st backward-whirl flap" in table


def test_multiblade_transform_round_trip():
    """T(t) T(t)^-1 = I and dT/dt equals the central difference of T (1e-6 relative), for
    3..6 blades; the coordinate names follow Nb (differential for even Nb)."""
    for nb in (3, 4, 5, 6):
        model = TurbineModel(rigid_hub_rotor(nb), elements=2)
        tr = MultiBladeTransform(model)
        t = 0.37
        I = (tr.matrix(t) @ tr.inverse(t)).toarray()
        np.testing.assert_allclose(I, np.eye(model.n), atol=1e-13)
        h = 1e-6
        fd = (tr.matrix(t + h) - tr.matrix(t - h)).toarray() / (2 * h)
        np.testing.assert_allclose(tr.rate(t).toarray(), fd, atol=1e-6 * model.rotor_speed)
        names = coordinate_names(nb)
        assert len(names) == nb and (names[-1] == "differential") == (nb % 2 == 0)
    with pytest.raises(ValueError, match="at least 3"):
        MultiBladeTransform(TurbineModel(PAPER, elements=2))


def test_a_wrong_relabelling_is_detected_and_not_used(monkeypatch):
    """The run-time guard: if the blade relabelling does not satisfy E(t + T/Nb) =
    S E(t) S^T (here: its transpose, the direction the code had before), periodic_dae warns
    and drops it; the full-period Floquet result then equals the correct Fast Floquet one
    (1e-8 per-rev, modes below 8 per-rev but the yaw zero)."""
    T = rigid_hub_rotor(3)
    good = modal_analysis(T, elements=3, method="radau")
    assert good.settings["fast"]
    real = TurbineModel.blade_relabelling
    monkeypatch.setattr(TurbineModel, "blade_relabelling",
                        lambda self: real(self).T.tocsr())
    with pytest.warns(RuntimeWarning, match="blade-relabelling symmetry"):
        bad = modal_analysis(T, elements=3, method="radau")
    assert not bad.settings["fast"]
    pick = lambda r: np.array(sorted(m.frequency_per_rev for m in r.modes
                                     if m.family != "yaw" and m.fixed_frame_per_rev < 8))
    np.testing.assert_allclose(pick(bad), pick(good), atol=1e-8)


def test_four_blades_on_a_teetering_hub_keep_collective_and_differential_apart():
    """Four Table 1 blades on the paper's teetering hub (no relabelling symmetry: full-period
    Floquet): the collective and the differential twist of the blade-local torsion modes are
    exactly degenerate and equal the single clamped blade (2.289345, 6.573183, 11.843707,
    17.095155 per-rev at N = 4; hawt_core.blade_modes, 1e-6 relative); each appears once as
    collective and once as differential (an eigen-solver returns any mix of a degenerate
    pair: the labels must not see two collective torsions at one frequency and none at the
    other)."""
    T = dc.replace(PAPER, rotor=dc.replace(PAPER.rotor, blades=4))
    r = modal_analysis(T, elements=4)
    single = [m.frequency_per_rev for m in blade_modes(T, 4).modes if m.family == "torsion"][:4]
    for sym in ("collective", "differential"):
        got = sorted(m.frequency_per_rev for m in r.modes
                     if m.family == "torsion" and m.symmetry == sym)
        np.testing.assert_allclose(got[:4], single, rtol=1e-6)


def test_three_blades_on_the_flexible_tower_file_fast_equals_full_period():
    """tests/data/three_blade_flexible_tower.yaml (gravity, tilt, precone, yaw spring and
    damper, flexible EA/GA blades, flexible tower; blades N = 2): Fast Floquet over T/3 gives
    the full-period Floquet exponents, labels and whirls of every mode below 15 per-rev (the
    same discretization: 1e-7 per-rev, the yaw spring's damped pair included).  Before the
    relabelling fix every elastic mode was labelled 'shear' and the yaw sat at 3 per-rev."""
    from hawt_core.io import load_turbine
    T = load_turbine("tests/data/three_blade_flexible_tower.yaml")
    fast = modal_analysis(T, elements=2, method="radau", fast=True)
    full = modal_analysis(T, elements=2, method="radau", fast=False)
    assert fast.settings["fast"] and not full.settings["fast"]
    pick = lambda r: [(m.family, m.symmetry, m.whirl, m.fixed_frame_per_rev, m.real_per_rev)
                      for m in r.modes if m.fixed_frame_per_rev < 15]
    a, b = pick(fast), pick(full)
    assert [x[:3] for x in a] == [x[:3] for x in b]
    np.testing.assert_allclose([x[3:] for x in a], [x[3:] for x in b], atol=1e-7)
    assert a[0][0] == "yaw" and all(x[0] != "shear" for x in a)


def test_a_cyclic_mode_below_one_per_rev_is_reported_positive_with_its_whirl_flipped():
    """Reference: Coleman's transform of identical, uncoupled blades (a rigid hub on a
    spinning shaft, yaw locked, no tower: each blade's root motion is prescribed).  A blade
    mode at f_rot per-rev in the rotating frame appears in the fixed frame as a collective
    mode at f_rot and a cyclic pair at f_rot + 1 (forward whirl) and f_rot - 1 (backward
    whirl).  With the blade's first lag mode below 1 per-rev (EI3 / 100: f_rot = 0.82 from
    the single clamped blade, hawt_core.blade_modes, an independent solver) the backward
    member's fixed-frame frequency is negative: it is reported as |f_rot - 1| = 0.18 per-rev
    with its whirl flipped to forward (its pattern turns with the rotor there, as a soft
    in-plane rotor's regressing lag mode does), while its blade-to-blade phase stays the
    rotating-frame pattern's: -360/Nb, opposite to the forward member's +360/Nb (the
    collective: 0).  Frequencies to 1e-9 per-rev."""
    T = rigid_hub_rotor(3, yaw_free=False)
    sec = T.blade.sections
    T = dc.replace(T, blade=dc.replace(T.blade, sections=dc.replace(sec, ei3=sec.ei3 * 0.01)))
    f_rot = next(m.frequency_per_rev for m in blade_modes(T, 4).modes if m.family == "lag")
    assert 0.5 < f_rot < 1.0
    r = modal_analysis(T, elements=4, method="hill", max_per_rev=4)
    lag = [m for m in r.modes if m.family == "lag"
           and abs(m.frequency_per_rev - f_rot) < 1e-9]
    by_fixed = {round(m.fixed_frame_per_rev, 6): m for m in lag}
    assert len(lag) == 3, [(m.fixed_frame_per_rev, m.whirl) for m in lag]
    low, mid, high = (by_fixed[round(f, 6)] for f in (1 - f_rot, f_rot, f_rot + 1))
    assert low.fixed_frame_per_rev == pytest.approx(1 - f_rot, abs=1e-9)
    assert high.fixed_frame_per_rev == pytest.approx(1 + f_rot, abs=1e-9)
    assert (low.whirl, mid.whirl, high.whirl) == ("forward", "collective", "forward")
    assert low.blade_phase_deg == pytest.approx(-120.0, abs=1e-6)
    assert high.blade_phase_deg == pytest.approx(120.0, abs=1e-6)
    assert mid.blade_phase_deg == pytest.approx(0.0, abs=1e-6)
    # a cyclic pair above 1 per-rev keeps its backward member backward, with -360/Nb
    bw = [m for m in r.modes if m.family == "lag" and m.whirl == "backward"]
    assert bw and all(m.blade_phase_deg == pytest.approx(-120.0, abs=1e-6) for m in bw)
    assert all(m.fixed_frame_per_rev == pytest.approx(m.frequency_per_rev - 1, abs=1e-9)
               for m in bw)
