"""Aeroelastic operating points (hawt_core/analyses/operating_points.py, ``hawt
operating-points``) of the NREL 5-MW under the schedule of ROSCO's DISCON.IN (the rosco wheel's).

References:
* Jonkman et al. 2009 (NREL/TP-500-38060), Table 7-1: the region-3 pitch that holds rated
  power, 3.83, 8.70, 14.92, 23.47 deg at 12, 14, 18, 25 m/s (FAST with a blade rigid in
  torsion); hawt's rotor with its blades 100 times stiffer must give them within 0.5 deg (no
  tilt or shear here, which FAST's include); the flexible blade, which twists towards feather
  under load, needs less pitch;
* the schedule's own laws: region 3 holds the rated generator power (1e-6); region 2 runs the
  optimal tip-speed ratio (1e-12) between the minimum and rated speed;
* mesh convergence of the tip deflection (N = 16 vs 32: 0.5 %).
"""
from __future__ import annotations

import json
import subprocess
import sys
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from test_aero_blade import nrel5mw
from test_bem import rosco_decks

from hawt_core.analyses.operating_points import operating_points
from hawt_core.io.discon import discon_schedule
from meshes import load_paper_mesh

JONKMAN_PITCH = {12.0: 3.83, 14.0: 8.70, 18.0: 14.92, 25.0: 23.47}


def schedule():
    return discon_schedule(rosco_decks() / "NREL-5MW" / "DISCON.IN")


def shipped():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_paper_mesh("nrel5mw", elements=16)    # operating_points' old default


def test_stiff_rotor_pitch_schedule_against_the_definition_report():
    s = schedule()
    t0 = shipped()
    stiff = nrel5mw(stiffness=100.0, precone=t0.rotor.precone)
    stiff = replace(stiff, rotor=replace(stiff.rotor, speed=t0.rotor.speed))
    winds = np.array(sorted(JONKMAN_PITCH))
    r = operating_points(stiff, winds, s, elements=16)
    for p in r.points:
        print(f"\n{p['wind_speed']:4.1f} m/s: pitch {p['pitch_deg']:6.2f} deg (report "
              f"{JONKMAN_PITCH[p['wind_speed']]:5.2f})", end="")
        assert p["converged"] and p["region"] == 3
        assert abs(p["pitch_deg"] - JONKMAN_PITCH[p["wind_speed"]]) < 0.5
        assert p["generator_power_kw"] == pytest.approx(s["rated_power"] / 1e3, rel=1e-6)
        assert p["rotor_speed_rpm"] == pytest.approx(s["rated_speed"] * 30 / np.pi, rel=1e-12)
    flexible = operating_points(t0, winds[:2], s, elements=16)
    for pf, ps in zip(flexible.points, r.points):
        assert pf["pitch_deg"] < ps["pitch_deg"] - 0.3      # elastic twist towards feather


def test_region_two_and_mesh_convergence():
    """8 m/s: the optimal tip-speed ratio, fine pitch, below rated power; with 8, 16, 32
    elements the tip deflection converges (each halving shrinks the change at least
    four-fold: 3.33, 2.99, 2.94 m) and power and thrust at 16 are within 0.1 % of 32."""
    s = schedule()
    t = shipped()
    R = t.hub.radius + t.blade.length
    a8, a, b = (operating_points(t, [8.0], s, elements=N).points[0] for N in (8, 16, 32))
    assert a["converged"] and a["region"] == 2 and a["pitch_deg"] == 0.0
    assert a["rotor_speed_rpm"] * np.pi / 30 * R / 8.0 == pytest.approx(s["tsr"], rel=1e-12)
    assert a["generator_power_kw"] < s["rated_power"] / 1e3
    d1 = abs(a8["tip_flap_m"] - a["tip_flap_m"])
    d2 = abs(a["tip_flap_m"] - b["tip_flap_m"])
    assert d1 / d2 > 4.0
    for key in ("aero_power_kw", "thrust_kn"):
        assert a[key] == pytest.approx(b[key], rel=1e-3)
    assert 0.4 < a["cp"] < 0.5 and 0.6 < a["ct"] < 0.9


def test_operating_points_command_line(tmp_path):
    """`--json` has the documented keys per point; a turbine without a controller file and
    no schedule values is a one-line error (exit 2)."""
    hawt = Path(sys.executable).parent / "hawt"
    out = subprocess.run([str(hawt), "operating-points", "nrel5mw", "--wind", "7:13:3",
                          "--json", "--plot", str(tmp_path / "op.png")], capture_output=True,
                         text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    keys = ("wind_speed", "rotor_speed_rpm", "pitch_deg", "aero_power_kw",
            "generator_power_kw", "thrust_kn", "cp", "ct", "tip_flap_m", "tip_edge_m",
            "converged")
    assert [p["wind_speed"] for p in data["points"]] == [7.0, 10.0, 13.0]
    for p in data["points"]:
        assert all(k in p for k in keys) and p["converged"]
    assert (tmp_path / "op.png").stat().st_size > 0
    bad = subprocess.run([str(hawt), "operating-points", "three-blade"], capture_output=True,
                         text=True, timeout=120)
    assert bad.returncode == 2 and "--controller" in bad.stderr
    assert len(bad.stderr.strip().splitlines()) == 1
