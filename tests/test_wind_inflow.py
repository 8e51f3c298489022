"""Wind field and dynamic inflow (hawt_core/aero/wind.py, inflow.py).

References, written in the test: potential flow past a cylinder (no flow through its surface,
irrotational and divergence-free, uniform far away); the power law; IEC 61400-1 ed. 3 eqs. 17-19
for the extreme operating gust (the class I-B amplitude at 25 m/s computed by hand, the
shape's zeros and its largest rise 0.74 V_gust at T/2); Oye's filter's closed-form step
response.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from hawt_core.aero.inflow import OYE_K, oye_rates, oye_steady, oye_time_constants
from hawt_core.aero.wind import ExtremeOperatingGust, Wind


def test_tower_shadow_is_potential_flow_past_the_tower():
    """Below the tower top, for a wind turned by 0.3 rad: no flow through the tower surface
    (1e-12 of U), zero divergence and curl in the horizontal plane (complex-step derivatives,
    1e-10), uniform flow 50 radii away (1e-3), and no shadow above the tower top."""
    U, R = 8.0, 3.0
    wind = Wind(speed=U, direction=0.3, tower_radius=R, origin_height=90.0,
                reference_height=90.0)
    th = np.linspace(0, 2 * np.pi, 37)
    surface = np.stack([np.full_like(th, -20.0), R * np.cos(th), R * np.sin(th)], -1)
    v = wind.velocity(0.0, surface)
    radial = surface[:, 1:] / R
    assert np.max(np.abs(np.sum(v[:, 1:] * radial, -1))) < 1e-12 * U
    # divergence and curl at points off the surface
    rng = np.random.default_rng(1)
    pts = np.stack([np.full(20, -30.0), rng.uniform(-15, 15, 20), rng.uniform(-15, 15, 20)], -1)
    pts = pts[np.hypot(pts[:, 1], pts[:, 2]) > 1.2 * R]
    h = 1e-30
    d = {}
    for j in (1, 2):
        e = np.zeros(3, complex)
        e[j] = 1j * h
        d[j] = wind.velocity(0.0, pts + e).imag / h          # d v / d p_j
    div = d[1][:, 1] + d[2][:, 2]
    curl = d[1][:, 2] - d[2][:, 1]
    assert np.max(np.abs(div)) < 1e-10 * U and np.max(np.abs(curl)) < 1e-10 * U
    far = wind.velocity(0.0, np.array([[-30.0, 150.0, 0.0], [-30.0, 0.0, -150.0]]))
    free = U * np.array([0.0, -math.sin(0.3), math.cos(0.3)])
    assert np.allclose(far, free, atol=1e-3 * U)
    above = wind.velocity(0.0, np.array([[5.0, 0.0, R * 1.01]]))
    assert np.allclose(above[0], free, rtol=1e-14)


def test_shear_history_and_direction():
    """Power law V(z) = V_ref (z / z_ref)^alpha (1e-14); a ramp and a step in the history
    (piecewise linear, 1e-14); the direction turns the wind about the vertical."""
    wind = Wind(speed=10.0, shear_exponent=0.2, reference_height=90.0, origin_height=90.0,
                history=((0.0, 1.0), (10.0, 1.2), (10.001, 0.8)))
    pts = np.array([[0.0, 0, 0], [-60.0, 0, 0], [40.0, 0, 0]])
    v = wind.velocity(0.0, pts)[:, 2]
    assert np.allclose(v, 10.0 * ((90.0 + pts[:, 0]) / 90.0) ** 0.2, rtol=1e-14)
    assert wind.hub_speed(5.0) == pytest.approx(11.0, rel=1e-14)
    assert wind.hub_speed(20.0) == pytest.approx(8.0, rel=1e-14)
    turned = Wind(speed=5.0, direction=0.5).velocity(0.0, np.zeros(3))
    assert np.allclose(turned, 5.0 * np.array([0.0, -math.sin(0.5), math.cos(0.5)]))
    with pytest.raises(ValueError, match="wind.speed"):
        Wind(speed=-1.0)
    with pytest.raises(ValueError, match="history"):
        Wind(speed=1.0, history=((1.0, 1.0), (0.5, 1.0)))


def test_a_wind_series_is_the_piecewise_linear_hub_speed():
    """``"t0:U0,t1:U1,..."`` (the node's ``wind`` parameter): the hub speed is the linear
    interpolation of the points (np.interp, constant beyond them; 1e-12), one plain speed a
    steady wind; bad series are refused naming the field, the text and what is allowed."""
    from hawt_core.aero.wind import parse_wind_series
    series = parse_wind_series("0:15,10:15,10.5:17,30:12")
    points = series.points
    assert series.gust_start is None and series.initial_speed == 15.0
    w = Wind.from_series(points, direction=0.1)
    t = np.linspace(-1.0, 40.0, 411)
    ts, us = zip(*points)
    np.testing.assert_allclose(w.hub_speed(t), np.interp(t, ts, us), rtol=1e-12)
    assert w.speed == 15.0 and w.direction == 0.1
    steady = Wind.from_series(parse_wind_series("12.5").points)
    assert steady.history == () and steady.speed == 12.5
    for text, words in [("0:15,5", ["wind", "'0:15,5'", "t0:U0"]),
                        ("3:15,1:16", ["increase"]), ("0:0", ["0.1 to 100 m/s"]),
                        ("0:nan", ["'0:nan'"]), ("11,eog@-1", ["gust's start"]),
                        ("11,eog@1,eog@2", ["one gust"]), ("eog@3", ["'eog@3'"])]:
        with pytest.raises(ValueError) as ei:
            parse_wind_series(text)
        assert all(x in str(ei.value) for x in words), str(ei.value)


def test_a_wind_series_with_the_extreme_operating_gust_on_the_nrel5mw():
    """``"11,eog@20"`` on the NREL 5-MW: 11 m/s plus the IEC 61400-1 ed. 3 extreme operating
    gust from 20 s, class I, turbulence B, its amplitude written out here from the standard
    (V_e1 = 0.8 x 1.4 x 50 m/s, sigma1 = 0.14 (0.75 V_hub + 5.6), Lambda1 = 42 m above 60 m;
    D = 2 (1.5 + 61.5 cos 2.5 deg) m, hub at 87.6 + 2.4 m): 4.92 m/s (1e-12), the hub speed
    its dip-rise-dip (1e-12) and 11 m/s outside it."""
    import warnings
    from hawt_core.aero.wind import parse_wind_series
    from hawt_core.io.catalog import load_any
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        turbine = load_any("nrel5mw")
    w = parse_wind_series("11,eog@20").for_turbine(turbine)
    D = 2 * (1.5 + 61.5 * math.cos(math.radians(2.5)))
    sigma1 = 0.14 * (0.75 * 11.0 + 5.6)
    amplitude = min(1.35 * (0.8 * 1.4 * 50.0 - 11.0), 3.3 * sigma1 / (1 + 0.1 * D / 42.0))
    assert w.gust.amplitude == pytest.approx(amplitude, rel=1e-12)
    assert amplitude == pytest.approx(4.92, abs=0.01)
    t = np.linspace(15.0, 35.0, 201)
    tt = t - 20.0
    inside = (tt >= 0) & (tt <= 10.5)
    dv = -0.37 * amplitude * np.sin(3 * np.pi * tt / 10.5) * (1 - np.cos(2 * np.pi * tt / 10.5))
    np.testing.assert_allclose(w.hub_speed(t), 11.0 + np.where(inside, dv, 0.0), rtol=1e-12)


def test_iec_extreme_operating_gust():
    """IEC 61400-1 ed. 3, class I-B, V_hub = 25 m/s, D = 126 m, z_hub = 90 m (the NREL 5-MW):
    by hand, V_e1 = 0.8 * 1.4 * 50 = 56, sigma1 = 0.14 (0.75 * 25 + 5.6) = 3.409,
    Lambda1 = 42, V_gust = min(1.35 * 31, 3.3 * 3.409 / (1 + 0.3)) = 8.6537 m/s; the shape
    -0.37 V_gust sin(3 pi t/T)(1 - cos(2 pi t/T)): zero at the ends, its largest rise at
    t = T/2 (0.74 V_gust) and its two dips (1e-12)."""
    g = ExtremeOperatingGust.iec(25.0, 126.0, 90.0, "I", "B", start=2.0)
    sigma1 = 0.14 * (0.75 * 25.0 + 5.6)
    assert g.amplitude == pytest.approx(3.3 * sigma1 / 1.3, rel=1e-12)
    assert g.amplitude == pytest.approx(8.6537, abs=1e-4)
    t = np.linspace(-1.0, 14.0, 150001)
    inc = g.increment(t)
    assert inc[0] == 0.0 and inc[-1] == 0.0
    assert g.increment(2.0 + 5.25) == pytest.approx(0.74 * g.amplitude, rel=1e-12)
    assert np.max(inc) == pytest.approx(0.74 * g.amplitude, rel=1e-9)
    assert np.min(inc) < -0.2 * g.amplitude
    with pytest.raises(ValueError, match="turbine_class"):
        ExtremeOperatingGust.iec(10.0, 100.0, 90.0, "IV")


def test_oye_step_response_closed_form():
    """A unit step of W_qs from rest: W_int = 1 - (1 - k) e^{-t/tau1} (the jump of k at once),
    W = 1 - e^{-t/tau2} - (1 - k) tau1 / (tau1 - tau2) (e^{-t/tau1} - e^{-t/tau2}), from
    integrating hawt's rates with DOP853 (1e-9); the steady state is W = W_qs."""
    tau1, tau2 = oye_time_constants(63.0, 11.0, 0.3, np.array([45.0]))
    tau1, tau2 = float(tau1), float(tau2[0])
    assert tau1 == pytest.approx(1.1 * 63.0 / ((1 - 0.39) * 11.0), rel=1e-14)
    assert tau2 == pytest.approx((0.39 - 0.26 * (45 / 63) ** 2) * tau1, rel=1e-14)

    def rhs(t, s):
        return np.array(oye_rates(s[0], s[1], 1.0, tau1, tau2))
    t = np.linspace(0.0, 60.0, 121)
    sol = solve_ivp(rhs, (0.0, 60.0), [0.0, 0.0], t_eval=t, method="DOP853", rtol=1e-12,
                    atol=1e-14)
    k = OYE_K
    w_int = sol.y[0] + k
    assert np.allclose(w_int, 1 - (1 - k) * np.exp(-t / tau1), atol=1e-9)
    W = 1 - np.exp(-t / tau2) - (1 - k) * tau1 / (tau1 - tau2) * (np.exp(-t / tau1)
                                                                   - np.exp(-t / tau2))
    assert np.allclose(sol.y[1], W, atol=1e-9)
    z, Ws = oye_steady(2.5)
    dz, dW = oye_rates(z, Ws, 2.5, tau1, tau2)
    assert abs(dz) < 1e-15 and abs(dW) < 1e-15 and Ws == 2.5
