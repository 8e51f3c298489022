"""Hill's method on the averaged system's modal basis (hawt_core/solvers/hill_reduced.py).

Reference: the whole-pencil search of hill.py (sparse shift-invert on the full Hill pencils
in frequency windows, then per-mode refinements, converged to a tighter tolerance) on the same
multi-blade system: an independent algorithm on the same equations.  The reduction keeps the
averaged pencil's modes within 1.5 bands, partitions each exponent's neighbourhood and adds
second-order corrections; its documented error is at most CORRECTION_TRUST (0.25) of those
corrections, below the truncation tolerance where it is used."""
import dataclasses as dc
import warnings

import numpy as np
import pytest

import hawt_core.solvers.hill as hill
import hawt_core.solvers.hill_reduced as hr
from hawt_core.aero.wind import Wind
from hawt_core.analyses.modal import _fourier_tol, periodic_dae
from hawt_core.assembly import TurbineModel
from hawt_core.io.catalog import shipped_controller
from hawt_core.io.discon import discon_schedule
from hawt_core.io.turbine_yaml import load_turbine
from hawt_core.numerics.pencil import equilibrate
from hawt_core.solvers.multiblade import MultiBladeTransform
from hawt_core.solvers.periodic import periodic_steady_state
from meshes import load_paper_mesh


def multiblade_system(turbine, elements, wind=None):
    """(mbc DAE, Fourier coefficients, observed rows, weights, rotor speed [rad/s])."""
    model = TurbineModel(turbine, elements=elements, wind=wind)
    mbc = MultiBladeTransform(model).dae(periodic_dae(model, periodic_steady_state(model)))
    rows, wts = model.display_rows()
    return mbc, mbc.fourier(tol=_fourier_tol(model)), rows, wts ** 2, model.rotor_speed


def modes(system, band_per_rev, tol=hill.CONVERGED_TOL, whole=False):
    """hill_modes on ``system`` (truncation "converged"); ``whole``: the whole-pencil search."""
    mbc, fc, rows, wts, omega = system
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return hill.hill_modes(mbc, band_per_rev * omega, observed=rows, weights=wts,
                               truncation="converged", coefficients=fc, converged_tol=tol,
                               modal_basis=not whole)


def agreement(got, ref, w):
    """Largest relative distance (to max(|eta|, w)) of each exponent of ``got`` from the
    nearest of ``ref``, and the smallest MAC of the matched harmonic-0 vectors."""
    worst, mac = 0.0, 1.0
    for i, eta in enumerate(got.exponents):
        j = int(np.argmin(np.abs(ref.exponents - eta)))
        worst = max(worst, abs(ref.exponents[j] - eta) / max(abs(eta), w))
        a = got.vectors[got.harmonics, :, i]
        b = ref.vectors[ref.harmonics, :, j]
        mac = min(mac, abs(np.vdot(a, b)) ** 2 / (np.vdot(a, a).real * np.vdot(b, b).real))
    return worst, mac


@pytest.fixture(scope="module")
def nrel_8ms():
    t = load_paper_mesh("nrel5mw")
    from hawt_core.analyses.operating_points import at_operating_point
    at, _ = at_operating_point(t, 8.0, discon_schedule(shipped_controller("nrel5mw")), None)
    return multiblade_system(at, 8, Wind(8.0))


def test_nrel5mw_in_wind_equals_the_whole_pencil(nrel_8ms, monkeypatch):
    """NREL 5-MW at its 8 m/s operating point (tower, drivetrain, gravity, tilt, BEM), 8
    elements, modes below 50 per-rev: the modal basis finds every exponent of the whole
    pencil (converged to 1e-7) within 2e-6 relative (measured 3.5e-7; the truncation
    tolerance is 5e-5), with the same vectors (MAC > 0.9999 in harmonic 0).  Without the
    out-of-basis correction the exponents are off by > 1e-5 (the term is needed and the
    test sees it)."""
    mbc, fc, rows, wts, omega = nrel_8ms
    w = mbc.omega
    got = modes(nrel_8ms, 50.0)
    ref = modes(nrel_8ms, 50.0, tol=1e-7, whole=True)
    assert got.method == "modal basis" and ref.method == "whole pencil"
    assert got.exponents.size == ref.exponents.size >= 25
    worst, mac = agreement(got, ref, w)
    assert worst <= 2e-6 and mac > 0.9999, (worst, mac)
    assert got.change <= hill.CONVERGED_TOL

    def no_correction(found, hill, mats, lu, sigma, E0, Xm, *args):
        L = 2 * hill.H + 1
        return [(eta, (Xm @ c.reshape(L, -1).T).T, 0.0, np.full(Xm.shape[0], np.nan))
                for eta, c, _ in found]
    monkeypatch.setattr(hr, "_out_of_basis", no_correction)
    crude = modes(nrel_8ms, 50.0)
    assert agreement(crude, ref, w)[0] > 1e-5


@pytest.mark.parametrize("dense", [False, True], ids=["arpack", "dense"])
def test_five_blades_with_gravity_and_tilt_equal_the_whole_pencil(dense, monkeypatch):
    """Five NREL 5-MW blades on its hub, tower and drivetrain, in a vacuum with gravity and
    the 5 deg tilt at 12.1 rpm, 6 elements, below 20 per-rev (multi-blade coordinates with
    two cyclic pairs and the 5 per-rev periodicity): the modal basis against the whole
    pencil (1e-7), 2e-6 relative; with the averaged spectrum from ARPACK and from one dense
    eigensolution (hill_reduced.DENSE_SHARE: the path a system with many slow aerodynamic
    states takes) alike."""
    if dense:
        monkeypatch.setattr(hr, "DENSE_SHARE", 0.0)
    t = load_paper_mesh("nrel5mw")
    five = dc.replace(t, rotor=dc.replace(t.rotor, blades=5))
    system = multiblade_system(five, 6)
    got = modes(system, 20.0)
    ref = modes(system, 20.0, tol=1e-7, whole=True)
    assert got.method == "modal basis"
    assert got.timings["dense"] == int(dense)          # the path asked for was taken
    assert got.exponents.size == ref.exponents.size >= 12
    worst, mac = agreement(got, ref, system[0].omega)
    assert worst <= 2e-6 and mac > 0.9999, (worst, mac)


def test_strongly_coupled_modes_are_refined_on_the_whole_pencil(nrel_8ms, monkeypatch):
    """The modes whose estimated reduction error exceeds the tolerance are refined one by one
    on the whole pencil (hill._reduced_modes).  The three lowest of the 8 m/s case (below
    20 per-rev) marked as too coupled: each refined exponent equals the whole-band search
    of the Hill pencil at the truncation its vector carries (1e-8 of max(|eta|, w): ARPACK
    on these index-3 pencils, refine_eigenpairs in numerics/pencil.py), beyond
    the reduction's; the other modes keep the reduction's exponents (1e-9: ARPACK's random
    start moves the basis slightly from run to run) and vectors
    (zero beyond its truncation)."""
    mbc, fc, rows, wts, omega = nrel_8ms
    w = mbc.omega
    plain = modes(nrel_8ms, 20.0)
    reduced = hill.reduced_converged_modes
    marked = []

    def too_coupled(*args, **kwargs):
        lam, V, tails, H, change, corr, part = reduced(*args, **kwargs)
        corr = corr.copy()
        corr[:3] = 1.0                    # sorted by frequency: the three lowest
        if not marked:      # the first basis (the wider one, tried next, refines the same)
            marked.extend([lam[:3].copy(), H])
        return lam, V, tails, H, change, corr, part
    monkeypatch.setattr(hill, "reduced_converged_modes", too_coupled)
    got = modes(nrel_8ms, 20.0)
    monkeypatch.undo()
    first, H = marked
    assert got.method == "modal basis" and got.harmonics > H
    refined = [int(np.argmin(np.abs(got.exponents - e))) for e in first]
    assert len(set(refined)) == 3
    whole = {}
    for i, eta in enumerate(got.exponents):
        v = got.vectors[:, :, i]
        inner = np.flatnonzero(np.abs(v).max(axis=1) > 0)
        Hi = (inner.max() - inner.min()) // 2              # the harmonics the mode carries
        if i in refined:
            assert Hi > H
            if Hi not in whole:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", RuntimeWarning)
                    whole[Hi] = hill.hill_modes(mbc, 20.0 * omega, harmonics=Hi,
                                                observed=rows, weights=wts,
                                                coefficients=fc).exponents
            assert np.abs(whole[Hi] - eta).min() <= 1e-8 * max(abs(eta), w), (eta, Hi)
        else:
            assert Hi == H
            assert np.abs(plain.exponents - eta).min() <= 1e-9 * max(abs(eta), w)


def test_defective_and_degenerate_averaged_pencils_fall_back_to_the_whole_pencil():
    """The reduction needs modal coordinates: a free yaw's double zero (the three-bladed
    Table 1 rotor with gravity and tilt) has none, and four flat-plate blades on a rigid hub
    in 7 m/s wind have cyclic modes exactly a base frequency apart (which exponent continues
    which mode is ambiguous).  Both raise ReductionFailed with that reason, and hill_modes
    answers with the whole pencil (whose results are checked against the monodromy in
    test_hill.py and test_aeroelastic_modes.py)."""
    from test_turbine_aero import teetering_rotor
    P = load_turbine("hawt_core/data/three_blade_rotor.yaml")
    free_yaw = dc.replace(P, gravity=dc.replace(P.gravity, enabled=True),
                          nacelle=dc.replace(P.nacelle, shaft_tilt=0.1))
    t = teetering_rotor(stiffness=1.0, gravity=True, tilt=0.1)
    four = dc.replace(t, rotor=dc.replace(t.rotor, blades=4), hub=dc.replace(t.hub, teeter=False))
    for system, band, reason in ((multiblade_system(free_yaw, 2), 8.0, "defective"),
                                 (multiblade_system(four, 2, Wind(7.0)), 6.0, "degenerate")):
        mbc, fc, rows, wts, omega = system
        with pytest.raises(hr.ReductionFailed, match=reason):
            hr.reduced_converged_modes(hill.coefficient_matrices(fc), mbc.n, mbc.omega,
                                       band * omega, rows, wts, {}, 5e-5, hill.MAX_HARMONICS)
        assert modes(system, band).method == "whole pencil"


@pytest.fixture(scope="module")
def nrel_8ms_lags():
    """NREL 5-MW (4 paper elements, tower, drivetrain, gravity, tilt) at 8 m/s with Oye's
    inflow and Jones's airfoils: (model, multi-blade DAE, Fourier coefficients, its modes
    below 3 per-rev on the modal basis, the averaged pencil's dense (E0, A0))."""
    from hawt_core.analyses.labels import aerodynamic_lags
    from hawt_core.analyses.operating_points import at_operating_point
    t = load_paper_mesh("nrel5mw")
    at, _ = at_operating_point(t, 8.0, discon_schedule(shipped_controller("nrel5mw")), None)
    model = TurbineModel(at, elements=4, wind=Wind(8.0), inflow="oye", airfoil="jones")
    mbc = MultiBladeTransform(model).dae(periodic_dae(model, periodic_steady_state(model)))
    rows, wts = model.display_rows()
    fc = mbc.fourier(tol=_fourier_tol(model))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        hm = hill.hill_modes(mbc, 3.0 * model.rotor_speed, observed=rows, weights=wts ** 2,
                             truncation="converged", coefficients=fc,
                             internal=aerodynamic_lags(model))
    E0, A0 = (m.real.toarray() for m in hill.coefficient_matrices(fc)[0])
    return model, mbc, fc, hm, E0, A0


def test_with_aerodynamic_lags_the_modal_basis_equals_the_whole_pencil(nrel_8ms_lags,
                                                                        monkeypatch):
    """NREL 5-MW (4 paper elements, tower, drivetrain, gravity, tilt) at 8 m/s with Oye's
    dynamic inflow and Jones's unsteady airfoils, modes below BAND per-rev.  Most averaged
    modes are the aerodynamic states' own lags, nearly equal and nearly parallel (no modal
    coordinates): the modal basis leaves them out (analyses/labels.aerodynamic_lags) and
    takes their response whole (hill_reduced._internal_tier).  Reference: the whole pencil
    converged to 1e-7, on the modes its windows resolve (|Re| <= w / 8; it has every mode
    found up to w / 5, five of them, and none at 0.29 w).  Every exponent found up to w / 5
    is within LAG_TOL (2e-4) of the reference's (measured 2.1e-5); every reference mode
    within w / 8 that oscillates in the blade frame is found (beyond LAG_OSCILLATION; the
    missing ones are the inflow lags, named "aerodynamic" anyway, and a collective inflow
    mode at -0.091 1/s whose flap is 1/4.5 of its inflow, a nearly parallel twin of a lag
    -0.0023 1/s away, taken whole with the lags: its cyclic twin is found); dropping the
    lags' response loses or moves exponents by > LAG_TOL (the term is needed and seen)."""
    from hawt_core.analyses.labels import LAG_OSCILLATION, aerodynamic_lags
    model, mbc, fc, *_ = nrel_8ms_lags
    rows, wts = model.display_rows()
    lags = aerodynamic_lags(model)
    Omega, w = model.rotor_speed, mbc.omega
    split = []
    tier_of = hr._internal_tier

    def tier(*args):
        mask, parts = tier_of(*args)
        split.append((int(mask.sum()), int((~mask).sum())))
        return mask, parts
    monkeypatch.setattr(hr, "_internal_tier", tier)

    def run(**kw):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            return hill.hill_modes(mbc, BAND * Omega, observed=rows, weights=wts ** 2,
                                   truncation="converged", coefficients=fc, **kw)
    got = run(internal=lags)
    assert got.method == "modal basis"
    assert split and split[0][0] > 3 * split[0][1], split   # lags outnumber the basis
    ref = run(converged_tol=1e-7, modal_basis=False)
    resolved = np.abs(ref.exponents.real) <= w / 8

    def distance(a, b):
        return np.array([np.min(np.abs(b - e)) / max(abs(e), w) for e in a])
    mine = got.exponents[np.abs(got.exponents.real) <= w / 5]
    assert mine.size >= 5
    assert distance(mine, ref.exponents).max() <= hill.LAG_TOL
    # the reference's modes not found: none oscillates in the blade frame (the lags, and a
    # non-oscillating inflow mode that drags the flap, a nearly parallel twin of a lag)
    missed = resolved & (distance(ref.exponents, got.exponents) > hill.LAG_TOL)
    off = np.abs(ref.exponents.imag - Omega * np.round(ref.exponents.imag / Omega))
    assert np.all(off[missed] <= LAG_OSCILLATION * np.abs(ref.exponents.real[missed]))

    def without_lags(av, marked, E0, eps, w):
        mask, (lam, X, Y) = tier_of(av, marked, E0, eps, w)
        return mask, (lam, X, 0.0 * Y)
    monkeypatch.setattr(hr, "_internal_tier", without_lags)
    crude = run(internal=lags).exponents
    assert crude.size < got.exponents.size or distance(mine, crude).max() > hill.LAG_TOL


#: The band of the aerodynamic-lag test [per-rev]: its whole-pencil reference takes 69 s
#: at 1.5 (229 s at 3)
BAND = 1.5


def test_slow_inflow_lags_that_beat_stay_out_of_the_modal_basis():
    """The shipped IEA 15-MW at 3 m/s with Oye's inflow and Jones's lags (3 elements of order
    6): Oye's slow lags of neighbouring elements (decay 0.009-0.044 1/s) couple into nearly
    degenerate clusters that beat at 0.13-0.28 of their decay rate, with nearly parallel
    vectors (|cos| 0.999): no modal coordinates.  They are the aerodynamic states' own modes
    (their inflow 400-600 times their structural motion over R; the structural modes there at
    most 7.2 times) and analyses/labels.aerodynamic_lags marks them (LAG_OSCILLATION 0.5):
    Hill's modal basis applies (with 0.1 it was refused as defective and the point searched
    the whole pencil for minutes).  Reference: the reduction's own defect test (no
    ReductionFailed) and the labels' test, which must mark every averaged mode below 0.05
    1/s with such an inflow."""
    from hawt_core.analyses.labels import _aerodynamic_sizes, aerodynamic_lags
    from hawt_core.analyses.operating_points import at_operating_point
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_any("iea15mw")
        at, _ = at_operating_point(t, 3.0, discon_schedule(shipped_controller("iea15mw")))
        model = TurbineModel(at, wind=Wind(3.0), inflow="oye", airfoil="jones")
        mbc = MultiBladeTransform(model).dae(periodic_dae(model,
                                                          periodic_steady_state(model)))
    rows, wts = model.display_rows()
    fc = mbc.fourier(tol=_fourier_tol(model))
    lags = aerodynamic_lags(model)
    seen = []

    def marking(lam, X):
        marked = lags(lam, X)
        inflow, _, structure = _aerodynamic_sizes(model, X)
        slow = (np.abs(lam) < 0.05) & (inflow > 100 * structure)
        seen.append((int(slow.sum()), bool(np.all(marked[slow]))))
        return marked
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        lam, *_ = hill._reduced_modes(fc, mbc.n, mbc.omega, 25 * model.rotor_speed,
                                      rows, wts ** 2, {}, hill.CONVERGED_TOL, marking)
    assert seen and seen[0][0] >= 6 and seen[0][1], seen
    assert lam.size >= 10


@pytest.mark.parametrize("coupling", [0.003, 0.03])
def test_a_nearly_degenerate_pair_is_continued_while_the_coupling_does_not_mix_it(coupling):
    """Two real averaged exponents 8.3e-4 w apart (two overdamped flap roots of the IEA
    15-MW at 22 m/s: -1.0203 and -1.0183 1/s, w = 2.364) and a complex pair, coupled by a
    periodic term of relative size ``coupling`` (harmonics +-1).  Reference: the eigenvalues
    of the same modal Hill pencil (H = 2) solved whole (scipy.linalg.eigvals).  Weakly
    coupled (3e-3: the pair mixes by ~3e-5 w against its 8e-4 w gap) each exponent continues
    its own mode: two distinct exponents, each within 1e-6 w of a whole-pencil eigenvalue
    (the partition keeps the coordinates farther than w to second order; the other member
    is 8e-4 w away); coupled ten times more the pair mixes and the continuation is refused
    (ReductionFailed), as is a pair within DEFECTIVE_SPLIT w whatever the coupling."""
    import scipy.linalg as sla
    w = 2.36364
    mu = np.array([-1.0202978, -1.0183294, -0.3 + 1.1j, -0.3 - 1.1j])
    rng = np.random.default_rng(7)
    G = coupling * w * (rng.standard_normal((4, 4)) + 1j * rng.standard_normal((4, 4)))
    Ar = {0: np.diag(mu), 1: G, -1: G.conj()}
    Er = {0: np.eye(4, dtype=complex), 1: np.zeros((4, 4)), -1: np.zeros((4, 4))}
    modal = hr._ModalHill(Ar, Er, mu, 2, w)
    whole = sla.eigvals(modal.Ah, modal.Eh)
    if coupling < 0.01:
        got = [modal.exponent(i, mu[i])[0] for i in (0, 1)]
        assert abs(got[0] - got[1]) > 5e-4 * w
        for e in got:
            assert np.min(np.abs(whole - e)) <= 1e-6 * w, (e, whole)
    else:
        with pytest.raises(hr.ReductionFailed, match="mixed by the coupling"):
            modal.exponent(0, mu[0])
    twins = hr._ModalHill(Ar, Er, np.array([mu[0], mu[0] + 1e-9, *mu[2:]]), 2, w)
    with pytest.raises(hr.ReductionFailed, match="ambiguous"):
        twins.exponent(0, mu[0])


def test_a_mode_damped_beyond_heavy_ratio_is_kept_within_its_reported_estimate():
    """The shipped IEA 15-MW at ROSCO's 11 m/s point with the frozen wake (the default): an
    air-damped flap root at -2.276 + 0.598i 1/s (damping ratio 0.97, |Re| = 0.96 w, below
    the |Re| > w of the heavy modes) was estimated at 1.1e-4 and refined on the whole Hill
    pencil at H = 2 and 3 (33 s of the point's 44 s; 8 s without).  It is now heavily damped
    by its ratio (hill.HEAVY_RATIO) and kept at HEAVY_TOL.  Reference: the whole Hill pencil
    at the same truncation (sparse shift-invert, hill._refine): the kept exponent is within
    the reported change (the largest estimate kept), and that is below HEAVY_TOL."""
    from hawt_core.analyses.operating_points import at_operating_point
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t = load_any("iea15mw")
        at, _ = at_operating_point(t, 11.0, discon_schedule(shipped_controller("iea15mw")))
        model = TurbineModel(at, wind=Wind(11.0))
        mbc = MultiBladeTransform(model).dae(periodic_dae(model,
                                                          periodic_steady_state(model)))
    rows, wts = model.display_rows()
    fc = mbc.fourier(tol=_fourier_tol(model))
    w, stats = mbc.omega, {}
    lam, V, tails, H, change, _ = hill._reduced_modes(
        fc, mbc.n, w, 25 * model.rotor_speed, rows, wts ** 2, stats, hill.CONVERGED_TOL)
    assert stats.get("factorizations", 0) <= 1, stats      # no whole-pencil refinement
    by_ratio = (np.abs(lam.real) <= w) & (np.abs(lam.real) > hill.HEAVY_RATIO * np.abs(lam)) \
        & (lam.imag > 0.05 * w)
    assert np.count_nonzero(by_ratio) >= 1, lam
    assert hill.CONVERGED_TOL < change <= hill.HEAVY_TOL
    Ah, Eh = hill.hill_pencil(fc, H)
    for eta in lam[by_ratio]:
        (ref, _, _), = hill._refine(Ah, Eh, [(eta, None, None, H, np.inf)], H, mbc.n, rows,
                                    wts ** 2, w, {})
        assert abs(ref - eta) / max(abs(eta), w) <= change, (eta, ref, change)


def _aero_rows(model):
    from hawt_core.analyses.labels import _aerodynamic_rows
    return np.concatenate(_aerodynamic_rows(model))


#: The aerodynamic states' slowing in the sensitivity reference (their rates' columns of E0
#: times 1 + SLOWED: their time constants longer by that share).
SLOWED = 1e-3


def _averaged_dense(model, E0, A0):
    """The averaged pencil equilibrated (row and column scalings: the same eigenvalues and
    participations; QZ on the raw pencil, whose algebraic columns are zero in E0, loses a
    tower mode's digits) and solved dense with both sides: (Es, lam, VL, VR) for Im >= 0,
    and ``move(j)``: |the move of lam[j] when the aerodynamic states are slowed by SLOWED|
    over SLOWED |lam[j]| (their participation in it, to first order)."""
    import scipy.linalg as sla
    aero = _aero_rows(model)
    As, Es, _ = equilibrate(A0, E0)
    lam, VL, VR = sla.eig(As, Es, left=True, right=True)
    ok = np.isfinite(lam) & (lam.imag >= -1e-9)
    lam, VL, VR = lam[ok], VL[:, ok], VR[:, ok]
    slowed = Es.copy()
    slowed[:, aero] *= 1 + SLOWED
    lam_s = sla.eigvals(As, slowed)
    lam_s = lam_s[np.isfinite(lam_s)]

    def move(j):
        return abs((lam_s[int(np.argmin(np.abs(lam_s - lam[j])))] - lam[j])
                   / (SLOWED * lam[j]))
    return Es, lam, VL, VR, move


def _partner(lam, eta, w):
    """The index of the averaged eigenvalue nearest the exponent ``eta`` (Im >= 0), or None
    when the periodic coupling moved it by more than 2e-2 w or another lies within 3 times
    that distance (no clear partner)."""
    d = np.abs(lam - eta)
    j, k = np.argsort(d)[:2]
    return None if d[j] > 2e-2 * w or d[k] < 3 * d[j] else int(j)


def test_participation_is_the_share_of_the_eigenvalue_the_aerodynamic_states_hold(
        nrel_8ms_lags):
    """Each mode's participation on the modal basis (hill_reduced._participation: its
    in-basis right and left vectors, harmonics summed) against two references on the
    averaged pencil (E0, A0), equilibrated and solved dense with both sides (scipy.linalg.eig,
    QZ): (1) the same
    definition (Perez-Arriaga et al. 1982, p_s = (E0^T conj(v_l))_s x_s, |.| normalized)
    from the dense eigenvectors: the aerodynamic states' share within 0.01 (measured 0.005:
    the exponents are the periodic system's, up to 1e-2 w from the averaged eigenvalues; a
    mode with no clear averaged partner is left out, at most a fifth);
    (2) the physics it stands for: slowing the aerodynamic states by 0.1 % (E0's columns of
    their rates x 1.001, their time constants longer) moves the averaged eigenvalue by
    -0.001 x lambda x their (complex) participation: a mode whose share is above 1/2 (the
    labels' AERODYNAMIC_PARTICIPATION) moves by more than half of the lags' own 0.1 %, one
    below by less.  Both kinds occur (a lag share >= 0.9 and <= 0.05)."""
    model, mbc, fc, hm, E0, A0 = nrel_8ms_lags
    assert hm.method == "modal basis" and hm.participation is not None
    P = hm.participation
    assert P.shape == (mbc.n, hm.exponents.size)
    np.testing.assert_allclose(P.sum(axis=0), 1.0, rtol=1e-12)
    aero = _aero_rows(model)
    Es, lam, VL, VR, move = _averaged_dense(model, E0, A0)
    shares = P[aero].sum(axis=0)
    matched = 0
    for i, eta in enumerate(hm.exponents):
        j = _partner(lam, eta, mbc.omega)
        if j is None:
            continue
        matched += 1
        p = np.abs((Es.T @ VL[:, j].conj()) * VR[:, j])
        p /= p.sum()
        assert abs(shares[i] - p[aero].sum()) <= 0.01, (eta, shares[i], p[aero].sum())
        assert (move(j) > 0.5) == (shares[i] > 0.5), (eta, shares[i], move(j))
    assert matched >= 0.8 * hm.exponents.size
    assert shares.max() >= 0.9 and shares.min() <= 0.05


def test_modes_are_labelled_aerodynamic_by_where_their_eigenvalue_lies(nrel_8ms_lags):
    """modal_analysis on the same turbine and wind (Hill's method in multi-blade
    coordinates on the modal basis): a mode is labelled 'aerodynamic' exactly when its
    eigenvalue belongs mostly to the blades' inflow and lag states.  Reference: the
    averaged pencil solved dense (equilibrated QZ) with the aerodynamic states slowed by
    0.1 %: a mode whose eigenvalue (its fixed-frame exponent, matched to the nearest dense
    eigenvalue) moves by more than half of -0.001 lambda is theirs.  Checks the plumbing
    from Hill's modes to the labels (columns, conjugates, real exponents)."""
    from hawt_core.analyses.modal import modal_analysis
    model, mbc, fc, hm, E0, A0 = nrel_8ms_lags
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = modal_analysis(model.turbine, elements=4, wind=Wind(8.0), inflow="oye",
                             airfoil="jones", max_per_rev=3.0)
    assert res.settings["method"] == "hill"
    _, lam, _, _, move = _averaged_dense(model, E0, A0)
    kinds, checked = set(), 0
    for m in res.modes:
        assert (m.aerodynamic_share > 0.5) == (m.family == "aerodynamic")
        assert m.to_dict()["aerodynamic_share"] == m.aerodynamic_share
        j = _partner(lam, complex(m.real_per_rev, abs(m.fixed_frame_per_rev))
                     * model.rotor_speed, mbc.omega)
        if j is None:
            continue
        assert (move(j) > 0.5) == (m.family == "aerodynamic"), (m.family, lam[j], move(j))
        kinds.add(m.family == "aerodynamic")
        checked += 1
    assert kinds == {True, False} and checked >= 0.8 * len(res.modes)
