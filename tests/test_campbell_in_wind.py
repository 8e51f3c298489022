"""Campbell diagrams in wind (issue 34, items 3 and 5): overdamped modes named and counted,
tracks that survive the pitch's drift of every shape, curves without harmonic run-away, the
default band, and the shipped NREL 5-MW's aeroelastic diagram complete and continuous.

References are stated per test: closed forms of a damped oscillator's roots, synthetic sweeps
whose assignment is known by construction, the blade's own clamped modes for the band."""
from __future__ import annotations

import numpy as np
import pytest

from hawt_core.analyses.campbell import (BAND_OVER_SECOND_FLAP, campbell_in_wind,
                                         default_wind_band, track_modes, unwrap_harmonics)
from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.analyses.labels import OVERDAMPED_ZETA, mark_overdamped, number_modes
from hawt_core.io.catalog import load_any, shipped_controller
from hawt_core.io.discon import discon_schedule
from hawt_core.results.modes import Mode
from hawt_core.results.plotting import mode_label


def _mode(family, symmetry, eta, whirl=None, order=None):
    """A Mode of rotating-frame exponent ``eta`` [per-rev] (rotor speed 1 rad/s)."""
    return Mode(family=family, symmetry=symmetry, index=0, frequency_per_rev=eta.imag,
                real_per_rev=eta.real, frequency_hz=eta.imag / (2 * np.pi),
                damping_ratio=-eta.real / abs(eta), whirl=whirl, cyclic_order=order)


def _roots(omega, zeta):
    """Closed form: the roots of s^2 + 2 zeta omega s + omega^2 (upper one for zeta < 1)."""
    if zeta < 1:
        return [complex(-zeta * omega, omega * np.sqrt(1 - zeta ** 2))]
    d = omega * np.sqrt(zeta ** 2 - 1)
    return [complex(-zeta * omega + d, 0.0), complex(-zeta * omega - d, 0.0)]


def test_overdamped_pairs_are_named_and_keep_the_family_count():
    """Reference: second-order closed forms.  Collective flap: the 1st mode at 2 per-rev with
    zeta = 1.5 (two real roots, -0.76 and -5.24 per-rev), the 2nd at 6 per-rev with zeta
    0.2; cyclic flap: the 1st at 2.2 per-rev, zeta 1.3 (real roots, their backward and
    forward members merged), the 2nd whirls at 6.3 / 6.5 per-rev; a lone real root (its
    partner beyond the band); the lightly damped edge modes.  Expected: the real roots named
    '1st ... (overdamped, slow/fast)' with the index of the mode they stand for, the cyclic
    pair counted in both whirls (the oscillatory 2nd flap is '2nd backward-whirl' and '2nd
    forward-whirl', not 1st), the lone root its own group's, the edge modes untouched."""
    modes = []
    for r in _roots(2.0, 1.5):
        modes.append(_mode("flap", "collective", r))
    modes.append(_mode("flap", "collective", _roots(6.0, 0.2)[0]))
    for r in _roots(2.2, 1.3):
        modes.append(_mode("flap", "forward-whirl", r, whirl="forward", order=1))
    modes.append(_mode("flap", "backward-whirl", _roots(6.3, 0.2)[0], "backward", 1))
    modes.append(_mode("flap", "forward-whirl", _roots(6.5, 0.2)[0], "forward", 1))
    modes.append(_mode("torsion", "collective", complex(-40.0, 0.0)))
    modes.append(_mode("lag", "collective", _roots(3.0, 0.01)[0]))
    modes.append(_mode("lag", "backward-whirl", _roots(2.9, 0.01)[0], "backward", 1))
    modes.append(_mode("aerodynamic", "inflow", complex(-3.0, 0.0)))
    mark_overdamped(modes)
    number_modes(modes)
    labels = [mode_label(m) for m in modes]
    assert labels == ["1st collective flap (overdamped, slow)",
                      "1st collective flap (overdamped, fast)",
                      "2nd collective flap",
                      "1st cyclic flap (overdamped, slow)",
                      "1st cyclic flap (overdamped, fast)",
                      "2nd backward-whirl flap", "2nd forward-whirl flap",
                      "1st collective torsion (overdamped)",
                      "1st collective lag", "1st backward-whirl lag",
                      "1st inflow aerodynamic"]
    assert modes[-1].overdamped is None           # an inflow state's real root is no mode's
    # the threshold: zeta just below OVERDAMPED_ZETA oscillates, at it is overdamped
    z = OVERDAMPED_ZETA
    near = [_mode("flap", "collective", complex(-z * 0.999, np.sqrt(1 - (z * 0.999) ** 2))),
            _mode("flap", "collective", complex(-1.0, np.sqrt(1 - z ** 2) * 0.99))]
    mark_overdamped(near)
    assert [m.overdamped for m in near] == [None, "root"]


def test_heavily_damped_mode_keeps_its_index_by_natural_frequency():
    """Reference: closed forms.  A 1st collective flap at 2 per-rev with zeta 0.95 has the
    damped frequency 0.62 per-rev, a 2nd at 4 per-rev with zeta 0.99 has 0.56: numbered by
    damped frequency the 2nd would be the 1st; by natural frequency (|eta|) they keep their
    order."""
    a = _mode("flap", "collective", _roots(2.0, 0.95)[0])
    b = _mode("flap", "collective", _roots(4.0, 0.99)[0])
    assert b.frequency_per_rev < a.frequency_per_rev
    number_modes([b, a])
    assert (a.index, b.index) == (1, 2)


def _point(vectors, freqs, labels, speed=1.0, wind=None):
    return {"speed": speed, "abscissa": speed if wind is None else wind,
            "modes": [{"label": lab, "family": "flap", "symmetry": "collective", "index": j + 1,
                       "frequency_per_rev": f / (speed / (2 * np.pi)), "frequency_hz": f,
                       "real_per_rev": -0.01, "damping_ratio": 0.01}
                      for j, (f, lab) in enumerate(zip(freqs, labels))],
            "vectors": np.column_stack(vectors)}


def test_a_drifting_shape_keeps_its_track_in_wind():
    """Reference: a synthetic sweep in wind whose assignment is known by construction: mode A
    steps a little into a new direction of its own at each of 15 wind speeds
    (v_k+1 ~ v_k + 0.45 q_k+1, the q orthonormal: MAC 0.83 between neighbours, below
    KEEP_MAC, and 0.83^k with its first shape: below the refusal threshold from the 10th
    point on), mode B stays.  The track's reference must follow the latest clear match (in
    wind every match; elsewhere one no other pairing comes near, CLEAR_SHARE), so A stays
    one track over all points: a reference held at the first point would refuse the last
    six (more than a fragment merge restores) and start 'A #2'."""
    rng = np.random.default_rng(11)
    Q, _ = np.linalg.qr(rng.normal(size=(40, 17)))
    b, q = Q[:, 0], Q[:, 1:]
    v = q[:, 0]
    pts = []
    for k in range(15):
        if k:
            v = v + 0.45 * q[:, k]
            v = v / np.linalg.norm(v)
        pts.append(_point([v, b], [1.0 + 0.01 * k, 2.0], ["A", "B"], speed=1.2,
                          wind=3.0 + k))
    first_last = abs(np.vdot(q[:, 0], pts[9]["vectors"][:, 0])) ** 2
    assert first_last < 0.2
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == ["A", "B"]
    assert all(t.present().all() for t in tracks)


def test_the_aerodynamic_states_lags_are_not_drawn():
    """A sweep in wind with the blades' inflow states (Oye): their own lags (family
    'aerodynamic', counted, not listed, in the mode tables) get no Campbell track, and the
    structural modes beside them keep theirs (reference: the assignment by construction)."""
    rng = np.random.default_rng(3)
    Q, _ = np.linalg.qr(rng.normal(size=(12, 3)))
    pts = []
    for k in range(4):
        p = _point([Q[:, 0], Q[:, 1], Q[:, 2]], [0.0, 0.6, 1.1], ["1st inflow aerodynamic",
                   "A", "B"], speed=1.0, wind=5.0 + k)
        p["modes"][0]["family"] = "aerodynamic"
        pts.append(p)
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == ["A", "B"]
    assert all(t.present().all() for t in tracks)


def test_unwrap_does_not_run_away_where_a_curve_levels_off():
    """Reference: a track that drops by 0.137 Hz between two coarse wind steps and then stays
    at 1.17 Hz (IEA 15-MW 2nd collective flap above rated, 7.52 rpm: 1P = 0.125 Hz): no
    whole per-rev shift belongs anywhere (the linear prediction from the drop would subtract
    1P a step); nor where it bends below rated; a +2 per-rev slip is still undone."""
    speeds = np.full(8, 0.7875)
    hz = np.array([1.405, 1.419, 1.447, 1.301, 1.164, 1.170, 1.172, 1.173])
    sh = unwrap_harmonics(speeds, hz * 2 * np.pi / speeds, abscissa=np.arange(8.0) * 2 + 3)
    np.testing.assert_array_equal(sh, np.zeros(8))
    jumped = hz * 2 * np.pi / speeds
    jumped[6] += 2.0
    sh = unwrap_harmonics(speeds, jumped, abscissa=np.arange(8.0) * 2 + 3)
    np.testing.assert_array_equal(sh, [0, 0, 0, 0, 0, 0, -2, 0])
    # the same mode from 6 to 11 m/s, 1 m/s apart, rotor speed rising to rated (1P 0.088 to
    # 0.125 Hz): a bend of 0.6-0.9 per-rev a step is physics, not a slip (with a tolerance of
    # 0.25 per-rev the linear prediction shifted three points by +1, +2, +3 per-rev)
    speeds = np.array([0.55, 0.59, 0.63, 0.68, 0.74, 0.79])
    hz = np.array([1.432, 1.447, 1.385, 1.301, 1.209, 1.164])
    sh = unwrap_harmonics(speeds, hz * 2 * np.pi / speeds, abscissa=np.arange(6.0) + 6)
    np.testing.assert_array_equal(sh, np.zeros(6))


def test_unwrap_does_not_run_away_after_a_steep_step():
    """Reference: a fixed-frame track of the IEA 15-MW in wind (Oye + Jones, 3:25:23) that
    falls 0.23 Hz from 10 to 11 m/s (the rotor reaching rated speed) and then stays at
    13.7-14.2 per-rev (1.72-1.78 Hz) to 25 m/s, moving at most 0.15 per-rev a step: from 11
    m/s on no whole per-rev shift belongs anywhere.  The linear prediction from the steep
    step asked for -2 per-rev at 12 m/s (within WIND_UNWRAP_TOL of it), and each next one
    for -2 more: the curve ran to -1.7 Hz.  A slip of a whole per-rev (SLIP) is still
    undone."""
    rpm = np.array([5.68, 6.39, 7.10] + [7.5237] * 14)
    speeds = rpm * np.pi / 30
    per_rev = np.array([21.3781, 18.6007, 15.4677, 13.7247, 13.8729, 13.9287, 13.9636,
                        13.9937, 14.0160, 14.0344, 14.0572, 14.0795, 14.1001, 14.1233,
                        14.1414, 14.1564, 14.1646])
    winds = np.arange(8.0, 25.0)
    sh = unwrap_harmonics(speeds, per_rev, abscissa=winds)
    np.testing.assert_array_equal(sh[3:], np.zeros(14))
    slipped = per_rev.copy()
    slipped[9] -= 1.0
    sh = unwrap_harmonics(speeds, slipped, abscissa=winds)
    assert sh[9] == 1.0 and not np.any(sh[10:])


def test_a_point_whose_trim_fails_is_kept_with_its_error():
    """Each point's operating point is trimmed in its own task (the pitch that holds rated
    power at the schedule's rotor speed).  A schedule whose pitch stops 8 deg above fine
    pitch cannot hold rated power at 20 m/s (17 deg needed): that point is kept with the
    trim's error (errors="skip") or raised (errors="raise", naming the wind), while the
    13 m/s point (region 3, 6-7 deg) is trimmed and analysed.  Reference for its pitch: the
    operating points of the same schedule solved as a sweep (analyses/operating_points.py),
    1e-9 deg."""
    import concurrent.futures as cf
    from hawt_core.analyses.operating_points import operating_points
    from meshes import load_paper_mesh
    t = load_paper_mesh("nrel5mw")
    sched = discon_schedule(shipped_controller("nrel5mw"))
    stuck = dict(sched, max_pitch=sched["fine_pitch"] + np.radians(8.0))
    with cf.ThreadPoolExecutor(2) as pool:
        res = campbell_in_wind(t, [13.0, 20.0], stuck, executor=pool, max_hz=1.5,
                               elements=4)
        with pytest.raises(ValueError, match="20 m/s"):
            campbell_in_wind(t, [13.0, 20.0], stuck, executor=pool, max_hz=1.5, elements=4,
                             errors="raise")
    ok, failed = res.points
    assert "error" not in ok and ok["modes"] and failed["error"].startswith("ValueError")
    assert "no operating point at 20 m/s" in failed["error"]
    ref = operating_points(t, [13.0], stuck).points[0]
    assert ref["region"] == 3 and 5.0 < ref["pitch_deg"] < 8.0
    assert res.settings["pitch_deg"][0] == pytest.approx(ref["pitch_deg"], abs=1e-9)
    assert np.isnan(res.settings["pitch_deg"][1])


@pytest.fixture(scope="module")
def nrel_in_wind():
    t = load_any("nrel5mw")
    sched = discon_schedule(shipped_controller("nrel5mw"))
    return t, campbell_in_wind(t, [5.0, 9.0, 13.0, 17.0, 21.0, 25.0], sched)


def test_default_band_is_the_second_flap_and_holds_every_mode_below(nrel_in_wind):
    """Reference: the blade's own clamped modes at the top rotor speed (blade_modes): the
    default band is BAND_OVER_SECOND_FLAP x its 2nd flap + 1P (NREL 5-MW: 3.2 Hz); every
    point reports modes at or below it and at least the 15 modes of the first two flap
    modes and the first edge mode of every whirl, the two tower modes of each plane's first
    and the drivetrain (nothing lost in the band)."""
    turbine, res = nrel_in_wind
    top = float(np.max(res.speeds))
    flaps = [m.frequency_hz for m in blade_modes(turbine, rotor_speed=top, count=12).modes
             if m.family == "flap"]
    band = BAND_OVER_SECOND_FLAP * sorted(flaps)[1] + top / (2 * np.pi)
    assert default_wind_band(turbine, top) == pytest.approx(band, rel=1e-12)
    assert res.settings["max_hz"] == pytest.approx(band, rel=1e-12)
    assert 2.8 < band < 3.5
    for p in res.points:
        f = [m["fixed_frame_hz"] for m in p["modes"]]
        assert max(f) <= band and len(f) >= 15


def test_nrel5mw_wind_sweep_tracks_are_complete_continuous_and_keep_their_labels(
        nrel_in_wind):
    """Reference: label continuity across a wind sweep (issue 34): on the shipped NREL 5-MW
    from 5 to 25 m/s (the rosco schedule's operating points, frozen-wake BEM) every track is
    found at every wind speed (a mode that vanishes or reappears under a new label fails),
    no fixed-frame curve moves by more than 0.25 Hz between neighbouring wind speeds (4 m/s
    apart; the largest physical move, the backward-whirl flap's, is 0.14 Hz), and every
    track of the first two flap modes and the first edge mode of each whirl (named after
    the vacuum blade's modes) and of the first tower modes and the 2nd fore-aft one carries
    its own label at every point (each point names its modes independently: the label of a
    MAC-tracked mode changes neither family nor index).  No track carries '#': the second
    mode named after the 1st flap (near 3 Hz from 13 m/s, its blades in the 1st flap's shape,
    its tower holding 0.76-0.80 of their strain energy) is the tower's at every point
    (wind_names.TOWER_HYBRID: self-consistency of the rule, not a peer's number)."""
    _, res = nrel_in_wind
    principal = {f"{k} {w} {f}" for k, f in (("1st", "flap"), ("2nd", "flap"), ("1st", "lag"))
                 for w in ("backward-whirl", "collective", "forward-whirl")}
    # the 2nd fore-aft tower bending (2.84 Hz, 97 % of the tower's strain energy in fore-aft
    # bending): named by the energy, not by its top's twist times the rotor radius
    principal |= {"1st side-side tower", "1st fore-aft tower", "2nd fore-aft tower"}
    labels = [t.label for t in res.tracks]
    assert principal <= set(labels), labels
    for t in res.tracks:
        assert t.present().all(), t.label
        f = t.hz("fixed")
        assert np.max(np.abs(np.diff(f))) < 0.25, (t.label, f)
        if t.label in principal:
            assert all(n == t.label for n in t.names), (t.label, t.names)
        assert "#" not in t.label, t.label
        if 2.9 < np.mean(f) < 3.2:
            assert all(n.endswith(" tower") for n in t.names), (t.label, t.names)


def test_an_overdamped_pair_reports_its_damping_ratio_and_natural_frequency():
    """Reference: closed form.  The roots of s^2 + 2 zeta w s + w^2 with w = 2 per-rev,
    zeta = 1.5 at a rotor speed of 0.8 rad/s: overdamped_pairs must give back zeta (1e-12)
    and w / 2 pi in Hz (w = 1.6 rad/s), and the mode table's name carries the root."""
    from hawt_core.results.tables import mode_name, overdamped_pairs
    modes = [_mode("flap", "collective", r) for r in _roots(2.0, 1.5)]
    mark_overdamped(modes)
    number_modes(modes)
    (a, b, zeta, f0), = overdamped_pairs(modes, 0.8)
    assert zeta == pytest.approx(1.5, rel=1e-12)
    assert f0 == pytest.approx(1.6 / (2 * np.pi), rel=1e-12)
    assert mode_name(a) == "1st collective flap (overdamped, slow)"


def test_points_in_wind_are_submitted_longest_first(monkeypatch):
    """Reference: the order known by construction.  A sweep's points in wind go to the
    executor in decreasing wind speed (the costlier first: no long point left to run alone
    at the end), the results back in the sweep's order; points in a vacuum keep theirs."""
    import concurrent.futures as cf
    from hawt_core.analyses import campbell as C

    class Recorder:
        def __init__(self):
            self.submitted = []

        def submit(self, fn, task):
            self.submitted.append(task["abscissa"])
            f = cf.Future()
            f.set_result(fn(task))
            return f

    monkeypatch.setattr(C, "campbell_point", lambda task: task)
    for wind, expected in ((object(), [25.0, 11.0, 3.0]), (None, [3.0, 25.0, 11.0])):
        ex = Recorder()
        tasks = [{"abscissa": a, "wind": wind} for a in (3.0, 25.0, 11.0)]
        results, failures, _ = C._run(tasks, ex, None, "points", lambda i: "")
        assert ex.submitted == expected and not failures
        assert [r["abscissa"] for r in results] == [3.0, 25.0, 11.0]


def test_track_names_in_wind_are_their_points_majority_and_unique():
    """Reference: a synthetic sweep in wind (4 points, three orthogonal shapes, assignment
    known by construction).  A track is named after the name its points give its mode most
    often (the first point's "B" loses to three "C"), Track.names keeps each point's own;
    labels stay unique when a point's own name carries a '#' already: two more tracks named
    "A" and "A #2" by their points become "A #2" and "A #3" (not two "A #2")."""
    Q, _ = np.linalg.qr(np.random.default_rng(3).normal(size=(12, 4)))
    pts = [_point([Q[:, 0], Q[:, 1], Q[:, 2], Q[:, 3]], [1.0, 2.0, 3.0, 4.0],
                  ["B" if k == 0 else "C", "A", "A", "A #2"], speed=1.0, wind=5.0 + k)
           for k in range(4)]
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == ["C", "A", "A #2", "A #3"]
    assert tracks[0].names == ["B", "C", "C", "C"]


def test_a_lightly_damped_second_mode_of_a_name_is_drawn(tmp_path, monkeypatch):
    """The default Campbell plot (tracks="table2") leaves a second track of one name ('#2')
    to --all-modes unless it is damped less than DRAWN_DUPLICATE_ZETA somewhere: a mode
    that matters for stability is drawn.  Reference: three tracks by construction (A; 'A #2'
    at damping 0.2, 'A #3' at 0.99): the plot labels A and 'A #2', not 'A #3'."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.axes
    from hawt_core.results.campbell import CampbellResult
    from hawt_core.results.plotting import DRAWN_DUPLICATE_ZETA
    assert 0.2 < DRAWN_DUPLICATE_ZETA < 0.99
    Q = np.eye(6)[:, :3]
    pts = []
    for k in range(3):
        p = _point([Q[:, 0], Q[:, 1], Q[:, 2]], [0.5, 1.0, 0.1], ["A", "A #2", "A #3"],
                   speed=1.0, wind=5.0 + k)
        for m, zeta in zip(p["modes"], (0.01, 0.2, 0.99)):
            m["index"], m["damping_ratio"] = 1, zeta
        pts.append(p)
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == ["A", "A #2", "A #3"]
    res = CampbellResult(speeds=np.ones(3), tracks=tracks, points=pts,
                         wind_speeds=np.array([5.0, 6.0, 7.0]))
    drawn = []
    real = matplotlib.axes.Axes.annotate

    def spy(self, text, *a, **k):
        drawn.append(text)
        return real(self, text, *a, **k)
    monkeypatch.setattr(matplotlib.axes.Axes, "annotate", spy)
    res.plot(tmp_path / "c.png")
    assert set(drawn) == {"A", "A #2"}, drawn
