"""ROSCO in the loop (hawt_core.control): its DISCON library called through ctypes, driving the
NREL 5-MW's pitch bearings and generator torque with the rotor speed free.

References, each test stating its tolerance:
* the deck's own controller file (the rosco wheel's NREL-5MW/DISCON.IN): rated generator
  power VS_RtPwr and rated generator speed VS_RefSpd (5 MW, 1173.7 rpm = 12.1 rpm at the
  rotor through WE_GearboxRatio = 97) above rated; the optimal tip-speed ratio VS_TSRopt
  below rated;
* ROSCO's own error messages (a DISCON.IN with a missing entry, from the wheel's examples).
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from hawt_core.aero.wind import Wind
from hawt_core.cli import main
from hawt_core.control.discon import (ControllerError, DisconController, Measurements,
                                      rosco_library)
from hawt_core.control.loop import ActuatorLimits
from hawt_core.io.catalog import rosco_test_cases, shipped_controller
from hawt_core.io.discon import read_discon
from test_turbine_aero import nrel5mw

pytestmark = pytest.mark.skipif(rosco_library() is None or shipped_controller("nrel5mw") is None,
                                reason="the rosco wheel (libdiscon.so, DISCON.IN) is not installed")


def discon():
    return read_discon(shipped_controller("nrel5mw"))


def test_rosco_holds_rated_power_and_speed_above_rated(tmp_path, capfd):
    """Reference: DISCON.IN's VS_RtPwr and VS_RefSpd.  `hawt simulate nrel5mw --wind 15
    --controller rosco` (4 elements, flexible tower, gravity, tilt, free yaw, Oye's inflow):
    over the last 2 s of 6 s, mean generator power within 1 % of VS_RtPwr, mean rotor speed
    within 1 % of VS_RefSpd / gearbox ratio, the generator speed the gearbox ratio times it
    (1e-9), the pitch collective and above 5 deg; the CSV has the documented columns, the
    JSON on stdout is JSON alone (what ROSCO prints goes to stderr), the plot is written."""
    out = tmp_path / "run.csv"
    assert main(["simulate", "nrel5mw", "--wind", "15", "--controller", "rosco",
                 "--duration", "6", "-n", "4", "-q", "--json", "-o", str(out),
                 "--plot", str(tmp_path / "run.png")]) == 0
    summary = json.loads(capfd.readouterr().out)
    assert summary["controller"].endswith("DISCON.IN") and summary["controller_calls"] > 100
    assert (tmp_path / "run.png").stat().st_size > 10000
    with open(out) as f:
        rows = list(csv.DictReader(f))
    cols = list(rows[0])
    for c in ("time", "wind_speed", "rotor_speed_rpm", "generator_speed_rpm",
              "generator_power_kw", "generator_torque_knm", "pitch1_deg", "pitch2_deg",
              "pitch3_deg", "tip1_flap_m", "root1_out_of_plane_knm", "tower_base_fore_aft_knm",
              "tower_base_side_side_knm"):
        assert c in cols
    H = {c: np.array([float(r[c]) for r in rows]) for c in cols}
    d = discon()
    last = H["time"] > H["time"][-1] - 2.0
    power = H["generator_power_kw"][last].mean() * 1e3
    rpm = H["rotor_speed_rpm"][last].mean()
    rated_rpm = d["VS_RefSpd"] / d["WE_GearboxRatio"] * 30 / math.pi
    assert abs(power - d["VS_RtPwr"]) < 1e-2 * d["VS_RtPwr"]
    assert abs(rpm - rated_rpm) < 1e-2 * rated_rpm
    gen = H["generator_speed_rpm"]
    # the generator turns at N times the gearbox input; the rotor adds the shaft's twist rate
    assert np.all(np.abs(gen / d["WE_GearboxRatio"] - H["rotor_speed_rpm"]) < 0.05)
    assert np.allclose(H["pitch1_deg"], H["pitch3_deg"]) and H["pitch1_deg"][-1] > 5.0


def test_rosco_tracks_the_optimal_tip_speed_ratio_below_rated():
    """Reference: DISCON.IN's VS_TSRopt (7.5).  NREL 5-MW at 8 m/s, 4 elements, rigid tower,
    started at the schedule's optimal-TSR point: after 6 s under ROSCO the tip-speed ratio
    is within 3 % of VS_TSRopt and the pitch at PC_FinePit within 0.1 deg."""
    from hawt_core.analyses.closed_loop import closed_loop
    d = discon()
    t = replace(nrel5mw(), tower=None)
    R = t.hub.radius + t.blade.length
    U = 8.0
    # the schedule's operating point at 8 m/s: VS_TSRopt at fine pitch
    loop = closed_loop(t, Wind(U), "rosco", discon=shipped_controller("nrel5mw"), elements=4)
    try:
        loop.run(6.0)
    finally:
        loop.close()
    H = loop.history()
    tsr = H["rotor_speed_rpm"][-1] * math.pi / 30 * R / U
    assert abs(tsr - d["VS_TSRopt"]) < 3e-2 * d["VS_TSRopt"]
    assert abs(H["pitch1_deg"][-1] - math.degrees(d["PC_FinePit"])) < 0.1


def test_a_controller_failure_stops_with_its_message():
    """ROSCO's own message for a DISCON.IN with a missing entry (the wheel's
    example_inputs/minimal_DISCON_err.IN) ends the run as a ControllerError; the library is
    not called again, closing is safe."""
    bad = rosco_test_cases().parent / "example_inputs" / "minimal_DISCON_err.IN"
    if not bad.is_file():
        pytest.skip("the rosco wheel's example_inputs are not installed")
    c = DisconController(bad, 0.05, 3)
    m = Measurements(time=0.0, pitch=np.zeros(3), generator_speed=100.0, rotor_speed=1.0,
                     generator_torque=4e4, electrical_power=4e6, shaft_power=4e6,
                     hub_wind=10.0)
    with pytest.raises(ControllerError, match="F_VSRefSpdCornerFreq"):
        c.step(m)
    with pytest.raises(ControllerError, match="failed before"):
        c.step(m)
    c.close()
    c.close()


def test_bad_controller_arguments_name_the_field(tmp_path):
    with pytest.raises(ValueError, match="controller input file: .* not found"):
        DisconController(tmp_path / "missing.IN", 0.05, 3)
    with pytest.raises(ValueError, match="dt: 0.0 is not allowed"):
        DisconController(shipped_controller("nrel5mw"), 0.0, 3)
    with pytest.raises(ValueError, match="n_blades: 2 is not allowed"):
        DisconController(shipped_controller("nrel5mw"), 0.05, 2)
    with pytest.raises(ValueError, match="controller library: .* not found"):
        DisconController(shipped_controller("nrel5mw"), 0.05, 3, library=tmp_path / "x.so")
    assert main(["simulate", "nrel5mw", "--controller", "rosco", "--duration", "1"]) == 2
    lim = ActuatorLimits(pitch_min=0.0, pitch_max=0.5, pitch_rate=0.1, torque_max=10.0)
    p, q, clipped = lim.clip([0.7, -0.1, 0.02], 12.0, np.zeros(3), 9.0, 1.0)
    assert np.allclose(p, [0.1, 0.0, 0.02]) and q == 10.0 and clipped == ["pitch", "torque"]


#: Jonkman, Butterfield, Musial & Scott, "Definition of a 5-MW Reference Wind Turbine for
#: Offshore System Development", NREL/TP-500-38060 (2009), Table 7-1: wind speed [m/s],
#: region-3 pitch [deg] at rated speed and power, dP/dtheta [MW/rad] (FAST linearization,
#: frozen wake).
JONKMAN_TABLE_7_1 = np.array([
    [12.0, 3.83, -43.73], [13.0, 6.60, -51.66], [14.0, 8.70, -58.44], [15.0, 10.45, -64.44],
    [16.0, 12.06, -70.46], [17.0, 13.54, -76.53], [18.0, 14.92, -83.94],
    [19.0, 16.23, -90.67], [20.0, 17.47, -94.71], [21.0, 18.70, -99.04],
    [22.0, 19.94, -105.90], [23.0, 21.18, -114.30], [24.0, 22.35, -120.20],
    [25.0, 23.47, -125.30]])


def test_builtin_gains_follow_jonkmans_baseline_design():
    """Reference: Jonkman et al. 2009 (NREL/TP-500-38060), section 7: drivetrain inertia
    43,784,725 kg m^2 (1 %), region-2 gain 0.0255764 N m/rpm^2 (5 %: hawt's BEM Cp), Table
    7-1's region-3 pitch (0.3 deg) and frozen-wake pitch sensitivity (5 %) at 12..25 m/s,
    and the PI gains KP = 0.01882681 s, KI = 0.008068634 (10 %) and theta_K = 6.302336 deg
    (15 %) that follow from them with w_n = 0.6 rad/s, zeta = 0.7 (the linear fit of the
    sensitivity magnifies its differences)."""
    from hawt_core.analyses.controller_design import (builtin_gains, pitch_sensitivity,
                                                      rotor_inertia)
    from hawt_core.io.discon import discon_schedule
    t = nrel5mw()
    s = discon_schedule(shipped_controller("nrel5mw"))
    N = t.drivetrain.gearbox_ratio
    J = rotor_inertia(t) + N * N * t.drivetrain.generator_inertia
    assert abs(J - 43784725.0) < 1e-2 * 43784725.0
    g = builtin_gains(t, s)
    k_rpm = g.k_opt * (math.pi / 30) ** 2
    assert abs(k_rpm - 0.0255764) < 5e-2 * 0.0255764
    ps = pitch_sensitivity(t, s, winds=JONKMAN_TABLE_7_1[:, 0])
    assert np.allclose(np.degrees(ps["pitch"]), JONKMAN_TABLE_7_1[:, 1], atol=0.3)
    assert np.allclose(ps["dp_dtheta"] / 1e6, JONKMAN_TABLE_7_1[:, 2], rtol=5e-2)
    assert abs(g.kp - 0.01882681) < 0.1 * 0.01882681
    assert abs(g.ki - 0.008068634) < 0.1 * 0.008068634
    assert abs(math.degrees(g.theta_k) - 6.302336) < 0.15 * 6.302336


@pytest.mark.parametrize("kind", ["builtin", "rosco"])
def test_a_wind_step_settles_at_rated_speed(kind):
    """Reference: DISCON.IN's VS_RefSpd and VS_RtPwr.  NREL 5-MW on a rigid tower, 4
    elements, Oye's inflow, 15 m/s stepping to 17 m/s over 0.5 s at t = 1 s: the rotor speed
    rises (the step is felt: > 0.3 % above rated), then settles; over the last 2 s of 12 s
    the mean rotor speed is within 1 % of rated and the mean generator power within 2 % of
    rated, the pitch higher than at the start (more wind: more feather)."""
    from hawt_core.analyses.closed_loop import closed_loop
    from hawt_core.io.discon import discon_schedule
    path = shipped_controller("nrel5mw")
    s = discon_schedule(path)
    t = replace(nrel5mw(), tower=None)
    wind = Wind(15.0, history=((0.0, 1.0), (1.0, 1.0), (1.5, 17.0 / 15.0), (100.0, 17.0 / 15.0)))
    # from the schedule's operating point at 15 m/s, as `hawt simulate --wind 15` starts
    loop = closed_loop(t, wind, kind, discon=path, elements=4)
    try:
        loop.run(12.0)
    finally:
        loop.close()
    H = loop.history()
    rated_rpm = s["rated_speed"] * 30 / math.pi
    assert H["wind_speed"][-1] == pytest.approx(17.0)
    assert H["rotor_speed_rpm"].max() > 1.003 * rated_rpm
    last = H["time"] > H["time"][-1] - 2.0
    assert abs(H["rotor_speed_rpm"][last].mean() - rated_rpm) < 1e-2 * rated_rpm
    assert abs(H["generator_power_kw"][last].mean() * 1e3 - s["rated_power"]) \
        < 2e-2 * s["rated_power"]
    assert H["pitch1_deg"][-1] > H["pitch1_deg"][0] + 1.0


def test_builtin_controller_without_a_controller_file(tmp_path, capfd):
    """A turbine file the rosco wheel has no DISCON.IN for (the NREL 5-MW written out, rigid
    tower) runs under `--controller builtin` with the schedule given as flags (rated power
    5000 kW, 12.1 rpm, TSR 7.55, efficiency 94.4 %): after 4 s at 15 m/s the rotor speed is
    within 1 % of 12.1 rpm and the power within 2 % of 5 MW; ROSCO is refused naming what to
    give."""
    from hawt_core.io import dump_turbine
    path = tmp_path / "five_mw.yaml"
    path.write_text(dump_turbine(replace(nrel5mw(), tower=None)))
    flags = ["--rated-power", "5000", "--rated-rpm", "12.1", "--tsr-opt", "7.55",
             "--efficiency", "94.4"]
    out = tmp_path / "run.csv"
    assert main(["simulate", str(path), "--wind", "15", "--controller", "builtin",
                 "--duration", "4", "-n", "4", "-q", "-o", str(out)] + flags) == 0
    with open(out) as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]
    assert abs(float(last["rotor_speed_rpm"]) - 12.1) < 1e-2 * 12.1
    assert abs(float(last["generator_power_kw"]) - 5000.0) < 2e-2 * 5000.0
    capfd.readouterr()
    assert main(["simulate", str(path), "--wind", "15", "--controller", "rosco",
                 "--duration", "1"] + flags) == 2
    assert "--controller builtin with --rated-power" in capfd.readouterr().err


def test_overrides_replace_the_controller_within_the_limits():
    """ClosedLoop.set_override (what the node's pitch_command/torque_command call): a torque
    of 1e6 N m is clipped to DISCON.IN's VS_MaxTq (and its rate VS_MaxRat) and counted, never
    applied raw; a pitch override is followed at PC_MaxRat; clear_override gives both back
    to ROSCO (its torque back at VS_RtTq within 2 % in 20 steps); a wrongly sized pitch is
    refused naming the field."""
    d = discon()
    t = replace(nrel5mw(), tower=None)
    from hawt_core.analyses.closed_loop import closed_loop
    loop = closed_loop(t, Wind(15.0), "rosco", discon=shipped_controller("nrel5mw"),
                       elements=4, record=True)
    try:
        loop.run(0.2)
        p0 = loop.last()["pitch1_deg"]
        loop.set_override(torque=1e6, pitch=math.radians(p0) + 0.05)
        for _ in range(10):
            loop.step()
            assert loop.last()["generator_torque_knm"] * 1e3 <= d["VS_MaxTq"] + 1e-6
        assert loop.clipped["torque"] >= 10 and "torque" in loop.last_clipped
        r = loop.rotor_state()                 # what the node's rotor_state carries
        assert r["pitch_override"] and r["torque_override"]
        assert r["generator_torque"] <= d["VS_MaxTq"] + 1e-6
        assert r["electrical_power"] == pytest.approx(d["VS_GenEff"] / 100
                                                      * r["mechanical_power"], rel=1e-12)
        assert np.all(r["tower_top_displacement"] == 0.0)          # a rigid tower
        H = loop.history()
        rate = np.diff(np.radians(H["pitch1_deg"][-10:])) / loop.dt
        assert np.all(rate <= d["PC_MaxRat"] * (1 + 1e-9))
        loop.clear_override()
        assert loop.override == {"pitch": None, "torque": None}
        assert not loop.rotor_state()["pitch_override"]
        for _ in range(20):
            loop.step()
        assert abs(loop.last()["generator_torque_knm"] * 1e3 - d["VS_RtTq"]) \
            < 2e-2 * d["VS_RtTq"]
        with pytest.raises(ValueError, match="pitch: .* is not allowed"):
            loop.set_override(pitch=[0.1, 0.2])
    finally:
        loop.close()


def test_a_new_wind_is_felt_and_followed():
    """ClosedLoop.set_wind (the node's wind topic): 15 -> 18 m/s at t = 0.5 s, NREL 5-MW on a
    rigid tower under ROSCO: the hub wind recorded is the new one from the next step, the
    rotor speeds up (> 0.3 % above rated) and ROSCO pitches to feather (> 1 deg more within
    4 s); a wind from behind the rotor is refused naming the field."""
    t = replace(nrel5mw(), tower=None)
    from hawt_core.analyses.closed_loop import closed_loop
    loop = closed_loop(t, Wind(15.0), "rosco", discon=shipped_controller("nrel5mw"),
                       elements=4)
    try:
        loop.run(0.5)
        p0 = loop.last()["pitch1_deg"]
        loop.set_wind(18.0)
        loop.step()
        assert loop.last()["wind_speed"] == pytest.approx(18.0)
        loop.run(4.0)
        H = loop.history()
        assert H["rotor_speed_rpm"].max() > 1.003 * 12.1
        assert loop.last()["pitch1_deg"] > p0 + 1.0
        with pytest.raises(ValueError, match="wind direction: .* not allowed"):
            loop.set_wind(10.0, direction=2.0)
    finally:
        loop.close()


def test_fine_pitch_above_rated_speeds_the_rotor_up_on_the_flexible_tower():
    """A pitch override to fine pitch (0 deg, clipped from -1 rad at PC_MinPit) in 15 m/s on
    the flexible tower: more aerodynamic torque than ROSCO's rated torque, so the rotor speeds
    up (the drivetrain's torsion rides on it): a least-squares slope > 0.3 rpm/s at fine
    pitch and > 13.5 rpm after 3 s, from 12.1.  The Newton iteration converges all the way
    (regression: with unit scales for the tower's section forces, ~3.5 MN for the tower-top weight alone (rotor 110 t and
    nacelle 240 t, Jonkman et al. 2009 Table 1-1), Newton increments at their round-off were
    taken for divergence and the step failed at 13.4 rpm); the tower's force scales are at
    least that weight."""
    from hawt_core.analyses.closed_loop import closed_loop
    loop = closed_loop(nrel5mw(), Wind(15.0), "rosco", discon=shipped_controller("nrel5mw"),
                       elements=4, record=True)
    try:
        tower = loop.model.layout.tower()
        assert loop.sim._scale[tower.F.ravel()].min() >= (110e3 + 240e3) * 9.80665
        loop.set_override(pitch=-1.0)
        loop.run(3.0)
        H = loop.history()
        at_fine = np.asarray(H["pitch1_deg"]) == 0.0
        assert at_fine[-20:].all() and min(H["pitch1_deg"]) == 0.0
        rpm = np.asarray(H["rotor_speed_rpm"])[at_fine]
        slope = np.polyfit(np.asarray(H["time"])[at_fine], rpm, 1)[0]
        assert slope > 0.3 and rpm[-1] > 13.5, (slope, rpm[-5:])
    finally:
        loop.close()


def test_simulate_follows_a_wind_series(tmp_path, capfd):
    """`hawt simulate nrel5mw --wind-series 0:15,1:15,1.5:17 --controller rosco`: the CSV's
    wind_speed is the series' linear interpolation at every recorded time (1e-9: it is the
    hub speed the controller reads), the rotor starts at the operating point of 15 m/s
    (12.1 rpm within 1 %, DISCON.IN's rated speed) and ROSCO pitches to feather after the
    step (> 1 deg more at 3 s); a bad series or one with --wind is refused naming the flag."""
    out = tmp_path / "series.csv"
    assert main(["simulate", "nrel5mw", "--wind-series", "0:15,1:15,1.5:17", "--controller",
                 "rosco", "--duration", "3", "-n", "4", "-q", "-o", str(out)]) == 0
    capfd.readouterr()
    with open(out) as f:
        rows = list(csv.DictReader(f))
    t = np.array([float(r["time"]) for r in rows])
    U = np.array([float(r["wind_speed"]) for r in rows])
    np.testing.assert_allclose(U, np.interp(t, [0, 1, 1.5], [15, 15, 17]), rtol=1e-9)
    rpm = float(rows[0]["rotor_speed_rpm"])
    assert abs(rpm - 12.1) < 0.01 * 12.1
    pitch = np.array([float(r["pitch1_deg"]) for r in rows])
    assert pitch[-1] > pitch[t <= 1.0][-1] + 1.0
    for argv, words in [(["--wind-series", "0:15,0:17"], ["--wind-series", "increase"]),
                        (["--wind-series", "0:15", "--wind", "15"], ["--wind-series",
                                                                     "instead of --wind"])]:
        assert main(["simulate", "nrel5mw", *argv, "--controller", "rosco",
                     "--duration", "1"]) == 2
        err = capfd.readouterr().err
        assert all(w in err for w in words), err
