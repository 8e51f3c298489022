"""Tests of the nonlinear time simulation (hawt_core.simulate).

Each test states its reference and tolerance. Runtime: about a minute on a busy 2-core machine.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import curve_fit

from hawt_core.assembly import TurbineModel
from hawt_core.blade_modes import blade_modes
from hawt_core.fem.beam import q_apply
from hawt_core.model import Beam, Gravity, Hub, Nacelle, Rotor, SectionTable, Turbine
from hawt_core.simulate import SimulationError, Simulator, parse_perturb

SEC = dict(mass=67.5772, i1=5, i2=1e-4, i3=4.9999, gj=21.8e3, ei2=4.36e6, ei3=21.8e6)


def paper(N=4, yaw_free=False, stiff=1.0, gravity=False, teeter=True):
    s = dict(SEC)
    for k in ("gj", "ei2", "ei3"):
        s[k] = s[k] * stiff
    return Turbine("paper", Rotor(), Hub(teeter=teeter), Nacelle(yaw_free=yaw_free),
                   Beam(8.42, SectionTable.uniform(**s), N), gravity=Gravity(enabled=gravity))


def fit_frequency(t, x, w0):
    """Least-squares sinusoid (+ offset) fit; returns the angular frequency."""
    f = lambda t, a, b, c, w: a * np.cos(w * t) + b * np.sin(w * t) + c
    a0 = 0.5 * (x.max() - x.min())
    p, _ = curve_fit(f, t, x, p0=[a0, 0.0, x.mean(), w0], maxfev=20000)
    return abs(p[3])


# ---------------------------------------------------------------- energy (Jacobi integral)
def jacobi_integral_run(model, deg, revs, **kw):
    """H = E - W_shaft: total energy (blades' kinetic + strain energy, hub kinetic energy)
    minus the work done by the shaft torque that holds Omega0 constant. With the yaw locked
    and no gravity, E - W_shaft = T2 - T0 + V (the Jacobi integral in the rotating frame) up
    to a constant. The torque is the s3 component of the moment the shaft puts on the hub,
    from the hub's angular-momentum balance with the blades' root loads (midpoint values)."""
    m, beam, rig = model, model.beam, model.rigid
    nr = m.nq + m.nu
    Rmm = beam.R[:, 3:, 3:]

    def energy(y, t):
        K = rig.hub_kinetic_energy(y[:m.nq], y[m.nq:nr], t)
        u, th, V, Om, F, M = beam.nodal(y[nr:].reshape(m.n_blades, beam.n))
        X = np.concatenate([beam._at_gauss(V), beam._at_gauss(Om)], -1)
        K += 0.5 * np.einsum("bngi,nij,bngj,ng->", X, beam.props.mass, X, beam.wa + beam.wb)
        thg = beam._at_gauss(th)
        Vs = 0.0
        for b in range(m.n_blades):
            for e in range(beam.N):   # kappa from the element's rotation constraint
                Q = sum(w * np.stack([q_apply(thg[b, e, g], ek) for ek in np.eye(3)], -1)
                        for g, w in enumerate(beam.w))
                kap = np.linalg.solve(beam.h[e] * Q, th[b, e + 1] - th[b, e])
                Vs += 0.5 * beam.h[e] * kap @ np.linalg.solve(Rmm[e], kap)
        return K + Vs

    def hub_momentum(y, t):
        k = rig._kin(y[:m.nq], y[m.nq:nr], t)
        H = k["fr"]["H"]
        return H @ rig.hub_inertia @ H.T @ k["w_H"], k

    sim = Simulator(model, step_deg=deg, **kw)
    d = sim.diff
    E0, W, out = energy(sim.y, 0.0), 0.0, [0.0]
    yp, tp = sim.y.copy(), 0.0
    for _ in range(int(round(revs * 360 / deg))):
        sim.step()
        t, h = sim.t, sim.t - tp
        ym = sim.y.copy()
        ym[d] = 0.5 * (yp[d] + sim.y[d])
        ym[~d] = sim._mid[-1][1]
        L1, _ = hub_momentum(sim.y, t)
        L0, _ = hub_momentum(yp, tp)
        _, k = hub_momentum(ym, tp + h / 2)
        B, rho = k["fr"]["B"], k["rho"]
        tot = np.zeros(3)
        for b in range(m.n_blades):
            bl = m.layout.blade(b)
            tot += np.cross(rho[b], B[b] @ ym[bl.root_force]) + B[b] @ ym[bl.root_moment]
        W += h * m.rotor_speed * ((L1 - L0) / h - tot) @ k["s3"]
        out.append(energy(sim.y, t) - E0 - W)
        yp, tp = sim.y.copy(), t
    return np.array(out), E0


def test_jacobi_integral_conserved():
    """Reference: H = E - W_shaft is constant for the yaw-locked rotor without gravity.
    Tolerance: max |H - H0| over 10 revolutions below 1e-5 of the energy at 4 and 2 degree
    steps. Finding: the residual ~3 J (3e-6 E) does NOT shrink with the step (see the xfail
    below and docs/simulation.md): it comes from the space discretization or from this energy
    bookkeeping, not from the time integrator."""
    model = TurbineModel(paper(N=4))
    flap = [md for md in blade_modes(model.turbine).modes if md.family == "flap"][0]
    drift = {}
    for deg in (4.0, 2.0):
        H, E0 = jacobi_integral_run(model, deg, 10, mode=flap, mode_amplitude=0.05,
                                    newton_tol=1e-10)
        drift[deg] = np.abs(H).max()
    print("Jacobi integral drift [J]:", drift, "ratio", drift[4.0] / drift[2.0], "E0", E0)
    assert drift[4.0] < 1e-5 * E0 and drift[2.0] < 1e-5 * E0
    if not 3.0 < drift[4.0] / drift[2.0] < 5.5:
        pytest.xfail(f"energy drift ratio {drift[4.0] / drift[2.0]:.2f} for a halved step "
                     "(expected ~4): the residual is step-independent (open issue)")


# ---------------------------------------------------------------- linear frequencies
def test_small_amplitude_frequencies_match_linear():
    """Reference: symmetric 1st flap from hawt_core.blade_modes (2.4346/rev) and the
    teeter frequency of the linearized yaw-locked rotor (generalized eigenvalues of (A, E),
    0.99901/rev). Tolerance 0.5 % (least-squares sinusoid fit of the tip flap / teeter)."""
    model = TurbineModel(paper(N=4))
    w0 = model.rotor_speed
    flap = [md for md in blade_modes(model.turbine).modes if md.family == "flap"][0]
    sim = Simulator(model, step_deg=2.0, mode=flap, mode_amplitude=0.01)
    sim.run(3 * model.period)
    h = sim.history()
    f_flap = fit_frequency(h["time"], h["blade0_u"][:, -1, 2], flap.frequency_per_rev * w0) / w0
    # teeter: linear reference from the pencil
    import scipy.linalg as sl
    E, A = model.linearize(model.steady_state())
    lam = sl.eigvals(A.toarray(), E.toarray())
    lam = lam[np.isfinite(lam)] / w0
    ref_teeter = lam.imag[np.argmin(np.abs(np.abs(lam.imag) - 1.0) + 1e3 * (lam.imag <= 0))]
    sim = Simulator(model, step_deg=2.0, perturb={"teeter": 0.002})
    sim.run(4 * model.period)
    h = sim.history()
    f_tee = fit_frequency(h["time"], h["teeter"], w0) / w0
    print(f"flap {f_flap:.5f} vs {flap.frequency_per_rev:.5f}; teeter {f_tee:.5f} vs "
          f"{ref_teeter:.5f}")
    assert abs(f_flap / flap.frequency_per_rev - 1) < 5e-3
    assert abs(f_tee / ref_teeter - 1) < 5e-3
    assert abs(ref_teeter - 0.99901) < 1e-4


# ---------------------------------------------------------------- order
def test_temporal_order_two():
    """Reference: the same run with a 0.25 degree step. Tolerance: the observed order
    log2(e(4 deg) / e(2 deg)) of the tip flap/teeter error at half a revolution is 2 +- 0.3."""
    model = TurbineModel(paper(N=4))
    T = 0.5 * model.period

    def final(deg):
        sim = Simulator(model, step_deg=deg, perturb={"teeter": 0.05, "teeter_rate": 0.1},
                        newton_tol=1e-11, record=False)
        sim.run(T)
        d = sim.blade_deflections()[0]
        return np.array([sim.named()["teeter"], d["u"][-1, 2] / 8.42, d["theta"][-1, 0]])

    ref = final(0.25)
    e4 = np.abs(final(4.0) - ref).max()
    e2 = np.abs(final(2.0) - ref).max()
    order = math.log2(e4 / e2)
    print(f"errors {e4:.3e} {e2:.3e} order {order:.3f}")
    assert 1.7 < order < 2.3


# ---------------------------------------------------------------- stiff-blade teeter
def test_stiff_blade_teeter_frequency():
    """Reference: sqrt((C - A) / B) per-rev with A, B, C the rotor's (blades + hub) moments of
    inertia about h1, h2, h3 computed here from Table 1 (= 0.99900737). Blades x1e4 stiffer,
    no teeter spring, yaw locked. Tolerance 1e-4 (relative), which separates 0.99901 from
    1.0 and from the wrong-sign 1.0010."""
    t = paper(N=2, stiff=1e4)
    L, e, m = 8.42, 1.8, SEC["mass"]
    x2 = ((e + L) ** 3 - e ** 3) / 3 * m
    A = 2 * SEC["i1"] * L + 50.0
    B = 2 * (SEC["i2"] * L + x2) + 50.0
    C = 2 * (SEC["i3"] * L + x2) + 5.0
    ref = math.sqrt((C - A) / B)
    assert abs(ref - 0.99900737) < 1e-8
    model = TurbineModel(t)
    sim = Simulator(model, step_deg=1.0, perturb={"teeter": 0.005})
    sim.run(5 * model.period)
    h = sim.history()
    f = fit_frequency(h["time"], h["teeter"], model.rotor_speed) / model.rotor_speed
    print(f"stiff-blade teeter {f:.7f} vs {ref:.7f}")
    assert abs(f / ref - 1) < 1e-4


# ---------------------------------------------------------------- gravity: periodic
def test_gravity_periodic_response():
    """Reference: with gravity the response from the periodic steady state (harmonic balance)
    repeats every rotor period. Tolerance: |y(2T) - y(T)| and |y(T) - y(0)| of the tip
    lead-lag deflection below 2 % of its peak-to-peak gravity oscillation."""
    model = TurbineModel(paper(N=2, gravity=True, teeter=False))
    sim = Simulator(model, step_deg=2.0, harmonics=4)
    n = 180
    sim.run(2 * model.period)
    h = sim.history()
    lag = h["blade0_u"][:, -1, 1]
    ptp = lag[: n + 1].max() - lag[: n + 1].min()
    d1 = np.abs(lag[n:2 * n + 1] - lag[: n + 1]).max()
    print(f"lag ptp {ptp:.3e} m, period-to-period {d1:.3e}")
    assert ptp > 1e-4
    assert d1 < 0.02 * ptp


# ---------------------------------------------------------------- errors
def test_bad_perturbation_and_newton_failure():
    """Reference: clear errors. Unknown perturbation names, locked DOFs, non-finite values and
    negative durations raise ValueError naming the field; an absurd step raises
    SimulationError with time, step and residual norm (never NaN)."""
    model = TurbineModel(paper(N=2))
    with pytest.raises(ValueError, match="perturb: unknown name 'tetter'"):
        Simulator(model, perturb={"tetter": 0.1})
    with pytest.raises(ValueError, match="yaw"):
        Simulator(model, perturb={"yaw": 0.1})           # yaw locked
    with pytest.raises(ValueError, match="perturb teeter"):
        Simulator(model, perturb={"teeter": float("nan")})
    with pytest.raises(ValueError, match="perturb: unknown name 'foo'"):
        parse_perturb("foo=1")
    sim = Simulator(model, step_deg=1.0, record=False)
    with pytest.raises(ValueError, match="duration"):
        sim.run(-1.0)
    with pytest.raises(SimulationError, match=r"step 1 from t = 0 s.*residual norm"):
        Simulator(model, step_deg=1.0, perturb={"teeter": 3.0, "teeter_rate": 500.0},
                  max_iter=2).step()


def test_outputs_csv(tmp_path):
    """named(), blade_deflections() shapes and the CSV header of save()."""
    model = TurbineModel(paper(N=2, yaw_free=True))
    sim = Simulator(model, step_deg=5.0, perturb={"teeter": 0.02, "yaw_rate": 0.01})
    sim.run(0.05)
    nm = sim.named()
    assert set(nm) == {"time", "azimuth", "yaw", "yaw_rate", "teeter", "teeter_rate"}
    bd = sim.blade_deflections()
    assert len(bd) == 2 and bd[0]["u"].shape == (3, 3) and bd[0]["root_force"].shape == (3,)
    p = tmp_path / "out.csv"
    sim.save(p)
    header = p.read_text().splitlines()[0].split(",")
    assert header[:6] == ["time", "azimuth", "yaw", "yaw_rate", "teeter", "teeter_rate"]
    assert "blade0_node2_u3" in header and "blade1_node1_theta1" in header
    s = sim.summary()
    assert s["steps"] == sim.steps and s["real_time_factor"] > 0
