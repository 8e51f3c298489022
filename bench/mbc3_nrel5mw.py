"""hawt against OpenFAST's linearization + MBC3 of the NREL 5-MW at 8 m/s, mode by mode.

Reference (numbers not produced here): OpenFAST v3.3 linearization of openfast_toolbox's
``data/NREL5MW/5MW_Land_Lin_Rotating`` (commit a39a3ac, Main.fst; ElastoDyn.dat at
243d5bf), 36 azimuths, MBC3; reported in issue 34.  Its switches: ElastoDyn + AeroDyn15,
BEMT with frozen wake, steady airfoils (AFAeroMod 1), 8 m/s, 9 rpm, pitch 0, generator
torque trimmed (CalcSteady, TrimCase 2); DOFs flap 1 and 2, edge 1, generator (GenDOF);
tower, drivetrain torsion (DrTrDOF) and yaw off; blade structural damping 0.477465 % of
critical on every blade mode; gravity and the 5 deg shaft tilt on.

hawt with the same switches: the shipped ``nrel5mw`` (the same blades, from the rosco
wheel's deck) with the tower rigid, the yaw locked, the shaft rigid (no DrTrDOF) with the
generator free, its torque trimmed by the steady state and its torque law's slope the
deck's (ServoDyn's simple variable-speed law, region 2: 2 VS_Rgn2K omega_g, which
OpenFAST's linearization keeps: its trim only offsets the torque), 9 rpm, pitch 0, frozen wake,
quasi-steady airfoils; the blade's structural damping from the deck (modal 0.477465 %,
docs/structural_damping.md); the blades rigid in torsion (GJ x 1e3), as ElastoDyn's blades
have no torsion degree of freedom (the "torsion flexible" column: hawt's full beams, whose
bending-torsion coupling takes 8 % of the edgewise damping).  Differences that remain: hawt's
blades are beams (the shapes follow the loads) where ElastoDyn has 3 assumed modes per blade
(the collective edge with the free generator: one shape held, ElastoDyn's way, is an upper
bound the beam's mode lies below; printed: the Rayleigh-Ritz series in the clamped blade's
modes, 2.257 Hz with ElastoDyn's degrees of freedom against OpenFAST's 2.256 Hz, 2.152 Hz
with the 2nd edge shape and the 3rd flap, and the estimate with ElastoDyn's own BldEdgSh
polynomial, 2.283 Hz); hawt's
quasi-steady airfoil has no unsteady lift lag either way.

    .venv/bin/python bench/mbc3_nrel5mw.py [--quasi-steady-only]
"""
from __future__ import annotations

import argparse
import dataclasses as dc
import math
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import numpy as np  # noqa: E402

from hawt_core.aero.wind import Wind  # noqa: E402
from hawt_core.analyses.modal import modal_analysis  # noqa: E402
from hawt_core.io.catalog import load_any  # noqa: E402

#: OpenFAST v3.3 MBC3 (issue 34): name -> (undamped natural frequency f0 [Hz], damping ratio)
OPENFAST = {
    "1st flap BW": (0.587830, 0.63106),
    "1st flap collective": (0.722483, 0.52529),
    "1st flap FW": (0.841645, 0.44010),
    "1st edge BW": (0.937126, 0.016344),
    "1st edge FW": (1.237131, 0.012359),
    "2nd flap BW": (1.837321, 0.15553),
    "2nd flap collective": (1.986991, 0.14288),
    "2nd flap FW": (2.133747, 0.13376),
    "1st edge collective (generator)": (2.256064, 0.022585),
}


DECK = Path(__file__).resolve().parents[1] / "tests" / "data" / "openfast" / "NREL5MW" / \
    "5MW_Land_Lin_Rotating" / "Main.fst"


def deck_slope() -> float:
    """The linearization deck's generator torque slope [N m s/rad, HSS]: its ServoDyn's simple
    variable-speed law (VSContrl = 1) at 9 rpm, region 2 (2 VS_Rgn2K omega_g), as hawt's
    OpenFAST importer reads it and OpenFAST linearizes it (the trim only offsets the torque)."""
    import warnings
    from hawt_core.io.openfast import read_openfast
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return read_openfast(DECK).turbine.drivetrain.generator_torque_slope


#: ElastoDyn's blades have no torsion: hawt's made rigid in torsion by this factor on GJ
#: (the 1st torsion from ~5.8 Hz to ~180 Hz, far above the compared modes)
TORSION_RIGID = 1e3


def case(damped: bool = True, generator: str = "prescribed", upright: bool = False,
         torsion_rigid: bool = True):
    """The shipped NREL 5-MW with the linearization's switches.  ``generator``
    "prescribed": no drivetrain (the rotor held at 9 rpm, hawt's default); "free": a rigid
    shaft and a free generator whose torque the steady state trims.  ``upright``: no gravity,
    tilt or precone (an axisymmetric rotor).  ``torsion_rigid``: GJ x TORSION_RIGID
    (ElastoDyn's blades have no torsion degree of freedom)."""
    t = load_any("nrel5mw")
    if torsion_rigid:
        sec = t.blade.sections
        t = dc.replace(t, blade=dc.replace(t.blade, sections=dc.replace(
            sec, gj=TORSION_RIGID * np.asarray(sec.gj, float))))
    t = dc.replace(t, tower=None,
                   nacelle=dc.replace(t.nacelle, yaw_free=False),
                   drivetrain=None if generator == "prescribed" else dc.replace(
                       t.drivetrain, stiffness=None, damping=0.0, generator="free",
                       generator_torque_slope=deck_slope()),
                   rotor=dc.replace(t.rotor, speed=9 * math.pi / 30, pitch=0.0))
    if upright:
        t = dc.replace(t, gravity=dc.replace(t.gravity, enabled=False),
                       nacelle=dc.replace(t.nacelle, shaft_tilt=0.0),
                       rotor=dc.replace(t.rotor, precone=0.0))
    return t if damped else t.without_structural_damping()


def match(modes):
    """hawt's mode for each OpenFAST row: (label, f0 [Hz], zeta) by family, index, whirl."""
    def pick(pred):
        c = [m for m in modes if pred(m)]
        return c[0] if c else None
    out = {}
    for name in OPENFAST:
        idx = 2 if name.startswith("2nd") else 1
        fam = "flap" if "flap" in name else "lag"
        whirl = "backward" if "BW" in name else "forward" if "FW" in name else "collective"
        m = pick(lambda m: m.family == fam and m.index == idx and m.whirl == whirl)
        if m is None:
            out[name] = None
            continue
        f = m.fixed_frame_hz if m.fixed_frame_hz is not None else m.frequency_hz
        z = m.fixed_frame_damping_ratio if m.fixed_frame_damping_ratio is not None \
            else m.damping_ratio
        wd = 2 * math.pi * f
        w0 = wd / math.sqrt(max(1e-12, 1 - z * z))
        out[name] = (f"{m.family} {m.index} {m.whirl}", w0 / (2 * math.pi), z)
    return out


def elastodyn_shape_estimate(t) -> tuple:
    """(clamped [Hz], with the free rotor [Hz]) of the collective edge with ElastoDyn's own
    assumed edge shape: the deck's BldEdgSh polynomial phi (NRELOffshrBsline5MW_Blade.dat),
    the clamped frequency by its Rayleigh quotient (EI_edge phi''^2, the centrifugal tension
    T phi'^2, the in-plane softening -Omega^2 m phi^2, over m phi^2), then coupled to the
    rigid rotor (two degrees of freedom, Rayleigh-Ritz: omega^2 = omega_c^2 / (1 - Nb S^2 /
    (J m_q)), S = int m r phi, m_q = int m phi^2, J the rotor's and the generator's
    inertia).  If it lands near OpenFAST's, the row's difference is ElastoDyn's shape, not
    the physics both codes share."""
    import re
    import numpy as np
    blade = DECK.parents[1] / "5MW_Baseline" / "NRELOffshrBsline5MW_Blade.dat"
    c = {int(k): float(v) for v, k in re.findall(r"^\s*(\S+)\s+BldEdgSh\((\d)\)",
                                                 blade.read_text(), re.M)}
    L = t.blade.length
    x = np.linspace(0.0, 1.0, 4001)
    s = x * L
    phi = sum(c[k] * x ** k for k in range(2, 7))
    d1 = sum(c[k] * k * x ** (k - 1) for k in range(2, 7)) / L
    d2 = sum(c[k] * k * (k - 1) * x ** (k - 2) for k in range(2, 7)) / L ** 2
    sec = t.blade.sections
    m = np.interp(x, sec.stations, sec.mass)
    ei = np.interp(x, sec.stations, sec.ei3)
    r = t.hub.radius + s * np.cos(t.rotor.precone)
    om = t.rotor.speed
    tension = om ** 2 * np.array([np.trapezoid(m[i:] * r[i:], s[i:]) for i in range(s.size)])
    mq = np.trapezoid(m * phi ** 2, s)
    kq = (np.trapezoid(ei * d2 ** 2, s) + np.trapezoid(tension * d1 ** 2, s) - om ** 2 * mq)
    nb = t.rotor.blades
    S = np.trapezoid(m * r * phi, s)
    J = (nb * np.trapezoid(m * r ** 2, s) + t.hub.inertia_longitudinal
         + t.drivetrain.gearbox_ratio ** 2 * t.drivetrain.generator_inertia)
    fc = math.sqrt(kq / mq) / (2 * math.pi)
    return fc, fc / math.sqrt(1.0 - nb * S ** 2 / (J * mq))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.parse_args()
    runs = {
        # every blade mode: the rotor held (hawt's prescribed speed), gravity and tilt on
        "held": dict(generator="prescribed"),
        "held, undamped structure": dict(generator="prescribed", damped=False),
        "held, torsion flexible": dict(generator="prescribed", torsion_rigid=False),
        # the collective edge with the generator: free generator, torque trimmed; upright
        # (no gravity, tilt or precone): with them the trimmed harmonic balance takes
        # 100-200 s (its Newton steps use the whole system's LU) and Hill's whole pencil,
        # which a free azimuth needs, misses the heavily damped 1st collective flap
        "free generator, upright": dict(generator="free", upright=True),
    }
    rows = {}
    for name, kw in runs.items():
        t = case(**kw)
        t0 = time.perf_counter()
        r = modal_analysis(t, wind=Wind(8.0), inflow="frozen", airfoil="quasi-steady",
                           max_per_rev=20)
        dt = time.perf_counter() - t0
        rows[name] = match(r.modes)
        torque = r.settings.get("generator_torque")
        print(f"hawt, {name}: {dt:.1f} s"
              + (f"; generator torque trimmed to {torque:.6g} N m (HSS)" if torque else ""))
    # the Rayleigh-Ritz series of tests/test_generator_trim.py (rigid rotor + the clamped
    # blade's modes): ElastoDyn's degrees of freedom, then more shapes
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
    from test_generator_trim import ritz_free_rotor_edge
    free = case(generator="free", upright=True, damped=False)
    blade_zeta = case().blade.damping.modal["edge"][0]        # the deck's, every blade mode
    ritz, zeta = ritz_free_rotor_edge(free, 5, blade_zeta=blade_zeta,
                                      torque_slope=free.drivetrain.generator_torque_slope)
    print(f"collective edge with a free rotor, Rayleigh-Ritz in the clamped blade's modes "
          f"(no air; the blades' {100 * blade_zeta:.4g} % and the torque law's slope): "
          f"ElastoDyn's set (1st, 2nd flap, one edge) {ritz[2]:.4f} Hz / {zeta[2]:.5f}, + "
          f"the 2nd edge {ritz[3]:.4f} Hz / {zeta[3]:.5f}, + the 3rd flap {ritz[4]:.4f} Hz / "
          f"{zeta[4]:.5f} (the frequency an upper bound of the beam's)")
    fe, ed = elastodyn_shape_estimate(case(generator="free", upright=True))
    print(f"the same with ElastoDyn's own edge shape (BldEdgSh; clamped {fe:.4f} Hz): "
          f"{ed:.4f} Hz (OpenFAST {OPENFAST['1st edge collective (generator)'][0]:.4f} Hz)")
    print(f"\n{'mode':<34}{'OpenFAST f0':>12}{'hawt f0':>10}{'diff':>8}"
          f"{'OpenFAST zeta':>15}{'hawt zeta':>11}{'diff':>8}{'undamped str.':>15}"
          f"{'torsion flexible':>18}")
    for name, (f_of, z_of) in OPENFAST.items():
        which = "free generator, upright" if "generator" in name else "held"
        h = rows[which][name]
        h0 = rows["held, undamped structure"][name] if which == "held" else None
        hf = rows["held, torsion flexible"][name] if which == "held" else None
        if h is None:
            print(f"{name:<34}{f_of:>12.4f}{'missing':>10}")
            continue
        flex = (f"{hf[1]:>9.4f} {100 * (hf[2] / z_of - 1):>6.1f}%" if hf else f"{'-':>17}")
        print(f"{name:<34}{f_of:>12.4f}{h[1]:>10.4f}{100 * (h[1] / f_of - 1):>7.2f}%"
              f"{z_of:>15.5f}{h[2]:>11.5f}{100 * (h[2] / z_of - 1):>7.1f}%"
              + (f"{h0[2]:>15.5f}" if h0 else f"{'-':>15}") + f" {flex}")


if __name__ == "__main__":
    main()
