"""Campbell diagrams (hawt_core/campbell.py), the turbine mode pictures and Campbell plot
(hawt_core/plotting.py) and the `hawt campbell` CLI.

Every test states its reference and tolerance.  The heavy fixtures (three direct modal
analyses and two 3-speed Campbell sweeps at N = 2 elements, 128 steps per period) are shared
by the module; the whole file runs in well under a minute on two cores.
"""
from __future__ import annotations

import concurrent.futures as cf
import csv

import numpy as np
import pytest

from hawt_core.analyses.blade_modes import blade_modes
from hawt_core.results.campbell import CSV_COLUMNS
from hawt_core.analyses.campbell import (campbell, campbell_point, check_speeds,
                                track_modes)
from hawt_core.cli import main
from hawt_core.io import load_turbine
from hawt_core.analyses.modal import modal_analysis
from hawt_core.results.plotting import mode_file_stem, plot_turbine_modes, table2_modes

ELEMENTS = 2
STEPS = 128
SPEEDS = (5.0, 6.0, 7.0)
PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def turbine():
    return load_turbine(None)


def sweep_steps(w):
    """Steps per period the sweep uses at speed w: STEPS at the highest speed, more below it
    so that the band in Hz (STEPS / 8 per-rev at the top speed) stays resolved."""
    return int(np.ceil(STEPS * max(SPEEDS) / w - 1e-9))


def band_hz():
    return STEPS / 8 * max(SPEEDS) / (2 * np.pi)


@pytest.fixture(scope="module")
def direct(turbine):
    """modal_analysis at each speed with the sweep's steps, modes above the band dropped."""
    out = {}
    for w in SPEEDS:
        r = modal_analysis(turbine, elements=ELEMENTS, rotor_speed=w, steps=sweep_steps(w))
        r.modes = [m for m in r.modes if m.frequency_hz <= band_hz()]
        out[w] = r
    return out


@pytest.fixture(scope="module")
def threaded(turbine):
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        return campbell(turbine, SPEEDS, elements=ELEMENTS, steps=STEPS, executor=pool)


@pytest.fixture(scope="module")
def processes(turbine):
    calls = []
    res = campbell(turbine, list(reversed(SPEEDS)), elements=ELEMENTS, steps=STEPS,
                   progress=lambda f, m: calls.append((f, m)))
    res.progress_calls = calls
    return res


def _pairs(modes):
    return np.array(sorted((m["frequency_per_rev"], m["real_per_rev"]) if isinstance(m, dict)
                           else (m.frequency_per_rev, m.real_per_rev) for m in modes))


@pytest.mark.parametrize("which", ["threaded", "processes"])
def test_same_frequencies_as_direct_modal_analysis(which, request, direct):
    """Reference: modal_analysis called directly at each speed (same elements; the steps per
    period scale as 1 / speed from STEPS at the top speed, so that one band in Hz is resolved
    at every speed; modes above it dropped).  Tolerance: 1e-10 per-rev on every frequency and
    real part (the same computation).  Every mode of every speed is in exactly one track."""
    res = request.getfixturevalue(which)
    assert np.allclose(res.speeds, SPEEDS, rtol=0, atol=0)
    assert res.settings["max_hz"] == pytest.approx(band_hz(), rel=1e-12)
    for i, w in enumerate(SPEEDS):
        ref = direct[w]
        assert res.points[i]["settings"]["steps"] == sweep_steps(w)
        got = _pairs(res.points[i]["modes"])
        exp = _pairs(ref.modes)
        assert got.shape == exp.shape
        np.testing.assert_allclose(got, exp, rtol=0, atol=1e-10)
        tracked = np.array(sorted((t.frequency_per_rev[i], t.real_per_rev[i])
                                  for t in res.tracks if t.present()[i]))
        np.testing.assert_allclose(tracked, exp, rtol=0, atol=1e-10)
        hz = np.sort([t.frequency_hz[i] for t in res.tracks if t.present()[i]])
        np.testing.assert_allclose(hz, np.sort([m.frequency_hz for m in ref.modes]),
                                   rtol=0, atol=1e-10 * w / (2 * np.pi) + 1e-14)


def test_process_pool_uses_workers_and_reports_progress(processes):
    """Reference: the default executor is a process pool (work done outside this process);
    progress goes from 0 to 1 with one call per speed plus the initial one (exact)."""
    import os
    assert all(p["pid"] != os.getpid() for p in processes.points)
    fr = [f for f, _ in processes.progress_calls]
    assert fr[0] == 0.0 and fr[-1] == 1.0 and len(fr) == len(SPEEDS) + 1
    assert fr == sorted(fr)


def test_tracks_keep_first_speed_labels(threaded, direct):
    """Reference: the labels of the modes at the first speed (direct analysis); every track
    starts there (no mode appears later at N = 2, 128 steps), and the MAC of each assignment
    is >= 0.2 (the acceptance threshold)."""
    assert len(threaded.tracks) == len(direct[SPEEDS[0]].modes)
    from hawt_core.results.plotting import mode_label
    assert [t.label for t in threaded.tracks] == [mode_label(m) for m in direct[SPEEDS[0]].modes]
    for t in threaded.tracks:
        assert t.present().all()
        assert np.all(t.mac[1:] >= 0.2)


def test_symmetric_flap_track_stiffens_and_matches_blade_modes(threaded, processes, turbine):
    """Reference: hawt_core.blade_modes.blade_modes (one blade clamped on the spinning hub:
    the symmetric flap modes do not couple with the rigid bodies), 1st flap mode at each
    speed; tolerance 1e-6 relative on the frequency in Hz.  Centrifugal stiffening: the
    track's frequency in Hz increases strictly with the rotor speed."""
    refs = [[m for m in blade_modes(turbine, elements=ELEMENTS, rotor_speed=w).modes
             if m.family == "flap"][0] for w in SPEEDS]
    for res in (threaded, processes):
        t = res.track("1st symmetric flap")
        assert t.family == "flap" and t.symmetry == "symmetric" and t.index == 1
        assert np.all(np.diff(t.frequency_hz) > 0)
        for i, ref in enumerate(refs):
            assert abs(t.frequency_hz[i] - ref.frequency_hz) <= 1e-6 * ref.frequency_hz
            assert abs(t.frequency_per_rev[i] - ref.frequency_per_rev) <= \
                1e-6 * ref.frequency_per_rev


def test_tracking_follows_permuted_and_missing_modes():
    """Reference: a synthetic sweep whose modes are reordered between speeds (random complex
    vectors, MAC near 1 with their own past, near 0 otherwise) and one mode that vanishes;
    the Hungarian assignment must restore the order exactly (labels and values exact)."""
    rng = np.random.default_rng(3)
    m, k = 40, 5
    V = rng.normal(size=(m, k)) + 1j * rng.normal(size=(m, k))
    labels = [f"mode {j}" for j in range(k)]

    def point(perm, freqs, noise):
        W = V[:, perm] * np.exp(1j * rng.uniform(0, 6, len(perm))) \
            + noise * (rng.normal(size=(m, len(perm))))
        return {"modes": [{"label": labels[p], "family": "flap", "symmetry": "symmetric",
                           "index": p + 1, "frequency_per_rev": freqs[p],
                           "frequency_hz": freqs[p], "real_per_rev": 0.0,
                           "damping_ratio": 0.0} for p in perm], "vectors": W}

    f = np.arange(1.0, k + 1.0)
    pts = [point([0, 1, 2, 3, 4], f, 0.0), point([3, 0, 4, 1, 2], f + 0.1, 0.05),
           point([2, 4, 0, 1], f + 0.2, 0.05)]
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == labels
    for j, t in enumerate(tracks):
        exp = [f[j], f[j] + 0.1, f[j] + 0.2 if j != 3 else np.nan]
        np.testing.assert_array_equal(t.frequency_hz, exp)
    assert not tracks[3].present()[2]


def test_a_veering_pair_with_mixed_vectors_keeps_its_tracks():
    """Reference: a synthetic veering (the assignment is known by construction).  Two modes
    with orthonormal vectors a, b at the first speed; at the second each has turned
    half-way towards a third direction of its own (c, d: motion the other mode never has),
    so each matches its own past with MAC 0.45 and the other's with MAC 0 (exactly); the
    frequencies move by 1 %.  Both must continue their tracks (two tracks, no new one): a
    refusal threshold above 0.45 would split them into four."""
    rng = np.random.default_rng(5)
    Qm, _ = np.linalg.qr(rng.normal(size=(30, 4)) + 1j * rng.normal(size=(30, 4)))
    a, b, c, d = Qm.T

    def point(vectors, freqs):
        return {"modes": [{"label": f"mode {j}", "family": "flap", "symmetry": "symmetric",
                           "index": j + 1, "frequency_per_rev": f, "frequency_hz": f,
                           "real_per_rev": 0.0, "damping_ratio": 0.0}
                          for j, f in enumerate(freqs)],
                "vectors": np.column_stack(vectors)}

    w = np.sqrt(0.45)
    turned = [w * a + np.sqrt(1 - w * w) * c, w * b + np.sqrt(1 - w * w) * d]
    pts = [point([a, b], [1.0, 1.2]), point(turned, [1.01, 1.19])]
    mac = abs(np.vdot(a, turned[0])) ** 2 / np.vdot(turned[0], turned[0]).real
    assert mac == pytest.approx(0.45, abs=1e-12) and abs(np.vdot(b, turned[0])) < 1e-12
    tracks = track_modes(pts)
    assert [t.label for t in tracks] == ["mode 0", "mode 1"]
    np.testing.assert_array_equal(tracks[0].frequency_hz, [1.0, 1.01])
    np.testing.assert_array_equal(tracks[1].frequency_hz, [1.2, 1.19])


def test_csv_header_and_row_count(processes, tmp_path):
    """Reference: one row per (speed, mode) = sum of the mode counts (exact), the header
    CSV_COLUMNS, speeds in rad/s and rpm (rpm = 60 w / 2 pi to 1e-9)."""
    path = tmp_path / "campbell.csv"
    processes.to_csv(path)
    with open(path) as f:
        rows = list(csv.reader(f))
    assert tuple(rows[0]) == CSV_COLUMNS
    body = rows[1:]
    assert len(body) == sum(len(p["modes"]) for p in processes.points)
    for r in body:
        w, n = float(r[0]), float(r[1])
        assert abs(n - 60 * w / (2 * np.pi)) < 1e-9
        assert float(r[0]) in SPEEDS
    assert {r[2] for r in body} == {t.label for t in processes.tracks}


def test_plots_write_pngs(processes, direct, tmp_path):
    """Reference: PNG signature and non-empty files; one file per Table 2 mode named
    NN_family[_symmetry]_index.png (exact names), the combined picture, the Campbell diagram."""
    res = direct[SPEEDS[1]]
    out = plot_turbine_modes(res, tmp_path / "modes")
    sel = table2_modes(res)
    assert [p.name for p in out] == [f"{mode_file_stem(i, m)}.png" for i, m in
                                     enumerate(sel, 1)]
    assert any(p.name.endswith("_torsion_symmetric_1.png") for p in out)
    for p in out:
        data = p.read_bytes()
        assert data.startswith(PNG) and len(data) > 5000
    one = res.plot(tmp_path / "few.png", modes=["teeter", "flap antisymmetric 1",
                                                ("torsion", "symmetric", 1)])
    assert len(one) == 1 and one[0].read_bytes().startswith(PNG)
    c = processes.plot(tmp_path / "campbell.png")
    data = open(c, "rb").read()
    assert data.startswith(PNG) and len(data) > 10000


def test_mode_snapshot_amplitudes(direct):
    """Reference: the 1st symmetric flap mode moves the blades only (no yaw, no teeter:
    the paper's Fig. 1); the drawn rigid angles are below 1e-6 of the largest blade
    deflection (tip-metre units)."""
    from hawt_core.results.plotting import mode_snapshots
    res = direct[SPEEDS[1]]
    m = res.find("flap", "symmetric", 1)
    t, ph, X = mode_snapshots(res, m)
    lay = res.model.layout
    R = res.model.turbine.hub.radius + res.model.turbine.blade.length
    blade = max(np.abs(X[:, lay.blade(k).u[1:]]).max() for k in range(2))
    rigid = R * np.abs(X[:, [lay["yaw"], lay["teeter"]]]).max()
    assert len(t) == 4 and ph[0] == 0.0
    assert rigid <= 1e-6 * blade


@pytest.mark.parametrize("spec, field", [
    ("abc:9:3", "START 'abc'"), ("3:x:3", "STOP 'x'"), ("3:9:1", "COUNT '1'"),
    ("3:9:two", "COUNT 'two'"), ("0:9:3", "START '0'"), ("-1:9:3", "START '-1'"),
    ("9:3:3", "STOP '3'"), ("3:9", "'3:9'")])
def test_bad_speeds_one_line_error(spec, field, capsys):
    """Reference: the CLI contract (one line on stderr naming the field and the value,
    exit status 2, nothing on stdout)."""
    rc = main(["campbell", "--speeds", spec])
    err = capsys.readouterr()
    assert rc == 2 and err.out == ""
    lines = err.err.strip().splitlines()
    assert len(lines) == 1 and "--speeds" in lines[0] and field in lines[0]


def test_api_rejects_bad_speeds(turbine):
    """Reference: ValueError naming the field 'speeds' (exact prefix)."""
    for bad in ([], [0.0], [-1.0, 2.0], [float("nan")], "fast"):
        with pytest.raises(ValueError, match="^speeds: "):
            check_speeds(bad)
    with pytest.raises(ValueError, match="^elements: "):
        campbell(turbine, [5.0], elements=0, executor=cf.ThreadPoolExecutor(1))


def test_cli_campbell_end_to_end(tmp_path, capsys):
    """Reference: `hawt campbell` at 2 speeds writes the CSV (header + one row per mode and
    speed) and the PNG and prints the table (exit status 0)."""
    c, p = tmp_path / "c.csv", tmp_path / "c.png"
    rc = main(["campbell", "--speeds", "5:6:2", "--elements", "2", "--steps", "128",
               "--csv", str(c), "--plot", str(p), "--workers", "2"])
    out = capsys.readouterr().out
    assert rc == 0 and "Campbell diagram" in out
    rows = c.read_text().strip().splitlines()
    assert rows[0].split(",") == list(CSV_COLUMNS) and len(rows) > 2 * 10
    assert p.read_bytes().startswith(PNG)


def test_worker_returns_plain_data(turbine):
    """Reference: the work unit's output pickles and holds only plain data (dicts, lists,
    numbers, strings, ndarrays): what crosses a process or cluster boundary."""
    import pickle
    out = pickle.loads(pickle.dumps(campbell_point({"turbine": turbine, "speed": 6.0,
                                                    "elements": 1, "steps": 64})))

    def plain(x):
        if isinstance(x, dict):
            return all(isinstance(k, str) and plain(v) for k, v in x.items())
        if isinstance(x, (list, tuple)):
            return all(plain(v) for v in x)
        return x is None or isinstance(x, (str, int, float, bool, np.ndarray, np.generic))
    assert plain(out)
    assert out["vectors"].shape[1] == len(out["modes"])


def test_unwrap_harmonics_restores_continuity():
    """Reference: a smooth track f(w) = 2.0 + 0.1 w [Hz] whose dominant per-rev value jumps
    by +2 and -1 per-rev at two speeds (the Floquet integer-per-rev ambiguity); the shifts
    undo the jumps exactly and leave the first value and absent points alone."""
    from hawt_core.analyses.campbell import unwrap_harmonics
    w = np.linspace(3.0, 9.0, 7)
    hz = 2.0 + 0.1 * w
    pr = hz * 2 * np.pi / w
    raw = pr.copy()
    raw[3] += 2.0
    raw[5] -= 1.0
    raw[4] = np.nan
    sh = unwrap_harmonics(w, raw)
    exp = np.array([0, 0, 0, -2, np.nan, 1, 0], float)
    np.testing.assert_array_equal(sh, exp)
    ok = np.isfinite(raw)
    np.testing.assert_allclose((raw + np.nan_to_num(sh))[ok], pr[ok], rtol=0, atol=1e-12)


def test_sweep_near_a_multiplier_coincidence_keeps_the_physical_frequency(turbine):
    """At N = 2, 128 steps, 7 rad/s the multiplier of the 1st antisymmetric lag (4.36/rev)
    nearly equals the 2nd torsion pair's and their eigenvectors mix: the marching's principal
    exponent is then 2 per-rev off.  The reported frequency is the dominant harmonic of the
    lag motion (u2, theta3) itself, so over 5..7 rad/s (below the teeter/yaw coalescence near
    8 rad/s) the track is one track (no '#2'), needs no harmonic shift at any speed (a shift
    would mean the table and the plot disagree by whole per-rev), is 4.36 per-rev at 7 rad/s
    (not 6.36), and its frequency is smooth (second differences in Hz < 2e-3 Hz on the uniform
    speed grid)."""
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        res = campbell(turbine, np.linspace(5.0, 7.0, 5), elements=ELEMENTS, steps=STEPS,
                       executor=pool)
    assert not any("#" in t.label for t in res.tracks)
    t = res.track("1st antisymmetric lag")
    assert t.present().all()
    np.testing.assert_array_equal(t.shift, 0)
    assert 4.3 < t.frequency_per_rev[-1] < 4.42
    assert np.nanmax(np.abs(np.diff(t.frequency_hz, 2))) < 2e-3


def test_failed_speed_is_skipped(turbine, monkeypatch):
    """Reference: an analysis that raises at one speed (patched modal_analysis, thread pool)
    leaves that speed without modes, with its error message, and the other speeds intact;
    errors='raise' re-raises it (exact)."""
    import hawt_core.analyses.campbell as campbell_module
    real = campbell_module.modal_analysis

    def flaky(turbine, rotor_speed=None, **kw):
        if rotor_speed == 5.5:
            raise RuntimeError("steady state: Newton did not converge (test)")
        return real(turbine, rotor_speed=rotor_speed, **kw)
    monkeypatch.setattr(campbell_module, "modal_analysis", flaky)
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        res = campbell(turbine, [5.0, 5.5, 6.0], elements=1, steps=64, executor=pool)
        assert [w for w, _ in res.failed] == [5.5]
        assert "converge" in res.failed[0][1]
        assert all(not t.present()[1] for t in res.tracks)
        assert res.points[0]["modes"] and res.points[2]["modes"]
        assert "analysis failed at 5.5 rad/s" in res.table()
        with pytest.raises(RuntimeError, match="converge"):
            campbell(turbine, [5.0, 5.5], elements=1, steps=64, executor=pool, errors="raise")


def test_harmonic_mac_invariance():
    """Reference: the Floquet ambiguity x = p e^{eta t} = (p e^{-ik Omega t}) e^{(eta+ik
    Omega) t}: re-indexing the Fourier coefficients by k = 2 (a multiple of the blade count)
    gives MAC 1 to 1e-12; a re-indexing by 1 is not tried for two blades (MAC < 0.5 for
    random coefficients), and without harmonics the plain MAC is used (exact 1 for a
    phase-rotated vector)."""
    from hawt_core.analyses.campbell import shifted_mac
    rng = np.random.default_rng(0)
    K, m = 4, 12
    C = np.zeros((2 * K + 1, m), complex)
    C[2:-2] = rng.normal(size=(2 * K - 3, m)) + 1j * rng.normal(size=(2 * K - 3, m))
    C2 = np.zeros_like(C)
    C2[:-2] = C[2:]                         # harmonics moved down by 2 (outer two are zero)
    C1 = np.zeros_like(C)
    C1[:-1] = C[1:]
    A = C[..., None]
    assert abs(shifted_mac(A, C2[..., None], 3, 2)[0, 0] - 1) < 1e-12
    assert shifted_mac(A, C2[..., None], 0, 1)[0, 0] < 0.5
    assert shifted_mac(A, C1[..., None], 3, 2)[0, 0] < 0.5
    v = rng.normal(size=(m, 1)) + 1j * rng.normal(size=(m, 1))
    assert abs(shifted_mac(v, v * np.exp(0.7j))[0, 0] - 1) < 1e-12


@pytest.fixture(scope="module")
def wide_sweep(turbine):
    """The paper's turbine, N = 4, 12 speeds over 3..9 rad/s (through the multiplier
    coincidences of lag and torsion modes near 6.5 and 8.6 rad/s), default steps."""
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        return campbell(turbine, np.linspace(3.0, 9.0, 12), elements=4, executor=pool)


def test_one_continuous_track_per_mode(wide_sweep):
    """Every mode below the band is one track present at every speed (no '#2' fragment, no
    track born at a higher speed); the band is fixed in Hz, so the highest modes at the top
    speed are also found at the lowest (where they are 3x higher in per-rev: the marching
    there uses 3x the steps); every curve is smooth: the second difference of its continuous
    frequency is below 1 % of the frequency on this uniform grid (a whole per-rev slip at
    3..9 rad/s would be 0.5..1.4 Hz, 3-10 %)."""
    res = wide_sweep
    assert not any("#" in t.label for t in res.tracks), [t.label for t in res.tracks]
    rng = res.settings["steps_range"]
    assert rng == (400, 1200)
    high = max(res.tracks, key=lambda t: t.continuous_hz[-1])
    assert high.continuous_hz[-1] / (res.speeds[-1] / (2 * np.pi)) > 35     # per-rev
    assert high.present()[0] and high.continuous_hz[0] <= res.settings["max_hz"]
    for t in res.tracks:
        assert t.present().all(), t.label
        c = t.continuous_hz
        if np.nanmax(c) > 0.5:
            assert np.max(np.abs(np.diff(c, 2))) < 0.01 * np.nanmax(c), t.label


def test_table_prints_what_the_plot_draws(wide_sweep):
    """The table's numbers are the tracks' continuous frequencies in the result's frame (the
    curves of the plot), to the printed 4 decimals."""
    res = wide_sweep
    lines = res.table().splitlines()[2:2 + len(res.speeds)]
    for i, line in enumerate(lines):
        vals = [float(x) for x in line.split()[2:]]
        exp = [t.hz(res.frame)[i] for t in res.tracks]
        np.testing.assert_allclose(vals, exp, atol=6e-5)


def test_real_pairs_are_twins_and_drawn_once(wide_sweep, tmp_path, monkeypatch):
    """The teeter pair (+-0.045 per-rev at 1 per-rev: a divergence and its decaying partner)
    and the free yaw angle's double zero are pairs of tracks with one frequency: marked as
    twins of each other; the plot draws each pair's frequency once and both dampings."""
    res = wide_sweep
    teeter = [t for t in res.tracks if t.family == "teeter"]
    yaw = [t for t in res.tracks if t.family == "yaw"]
    assert len(teeter) == 2 and teeter[0].twin == teeter[1].label
    assert teeter[1].twin == teeter[0].label
    assert len(yaw) == 2 and yaw[0].twin == yaw[1].label
    assert np.allclose(teeter[0].real_per_rev, -teeter[1].real_per_rev, rtol=1e-6)
    assert all(t.twin is None for t in res.tracks if t.family not in ("teeter", "yaw"))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.axes
    calls = []
    real_plot = matplotlib.axes.Axes.plot

    def spy(self, *a, **k):
        calls.append((self, a))
        return real_plot(self, *a, **k)
    monkeypatch.setattr(matplotlib.axes.Axes, "plot", spy)
    res.plot(tmp_path / "c.png", tracks="all")
    assert len({id(c[0]) for c in calls}) == 2
    freq_ax = calls[0][0]                       # the rays are drawn first, on the top panel
    same = lambda a, c: (len(a) >= 2 and np.shape(a[1]) == np.shape(c)
                         and np.allclose(np.asarray(a[1], float), c, equal_nan=True))
    on_freq = [a for ax, a in calls if ax is freq_ax and same(a, teeter[0].continuous_hz)]
    on_damp = [a for ax, a in calls if ax is not freq_ax and (
        same(a, teeter[0].damping_ratio) or same(a, teeter[1].damping_ratio))]
    assert len(on_freq) == 1 and len(on_damp) == 2


def test_labels_are_spread_apart():
    """_spread keeps the order, separates the labels by at least the gap, stays in bounds
    and moves nothing that did not overlap."""
    from hawt_core.results.plotting import _spread
    y = np.array([1.0, 1.01, 1.02, 5.0, 9.99, 10.0])
    z = _spread(y, 0.2, 0.0, 10.0)
    assert np.all(np.diff(z[np.argsort(y)]) >= 0.2 - 1e-12)
    assert z.min() >= 0 and z.max() <= 10.0
    assert z[3] == 5.0


def test_fixed_frame_campbell_of_a_three_bladed_rotor():
    """Three blades on a rigid hub, free yaw (multi-blade coordinates): the default frame is
    the fixed one; each track's fixed-frame curve equals modal_analysis' fixed_frame_hz at
    each speed (1e-9 Hz), and an uncoupled cyclic torsion pair sits 1 per-rev above and below
    the collective torsion (forward, backward whirl; 1e-6 per-rev)."""
    import dataclasses as dc
    T = load_turbine()
    T = dc.replace(T, rotor=dc.replace(T.rotor, blades=3),
                   hub=dc.replace(T.hub, teeter=False, inertia_lateral=1e-9,
                                  inertia_longitudinal=1e-9))
    speeds = (5.0, 6.0, 7.0)
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        res = campbell(T, speeds, elements=3, executor=pool, max_hz=12.0)
    assert res.frame == "fixed"
    for i, w in enumerate(speeds):
        ref = modal_analysis(T, elements=3, rotor_speed=w, max_per_rev=1.05 * 12 * 2 * np.pi / w)
        want = sorted(m.fixed_frame_hz for m in ref.modes if m.fixed_frame_hz <= 12.0)
        got = sorted(t.hz("fixed")[i] for t in res.tracks if t.present()[i])
        np.testing.assert_allclose(got, want, atol=1e-9)
    coll = res.track("1st collective torsion")
    bw = res.track("1st backward-whirl torsion")
    fw = res.track("1st forward-whirl torsion")
    rev = np.array(speeds) / (2 * np.pi)
    np.testing.assert_allclose((fw.hz("fixed") - coll.hz("fixed")) / rev, 1.0, atol=1e-3)
    np.testing.assert_allclose((coll.hz("fixed") - bw.hz("fixed")) / rev, 1.0, atol=1e-3)
    with pytest.raises(ValueError, match="frame"):
        campbell(load_turbine(), speeds, elements=2, frame="fixed")
