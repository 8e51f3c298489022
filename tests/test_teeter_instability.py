"""The teeter pair's positive real part (Table 2: +0.045299 per-rev; hawt's Floquet analysis:
+0.045268) is physics of the model, seen by an independent route: the NONLINEAR time
simulation of the free-yaw, teetering rotor (no linearization, no Floquet theory) diverges
from a small teeter perturbation at exactly that exponential rate."""
import numpy as np
import pytest

from hawt_core.assembly import TurbineModel
from hawt_core.io import load_turbine
from hawt_core.modal import modal_analysis
from hawt_core.simulate import Simulator


def test_simulated_yaw_teeter_divergence_grows_at_the_floquet_rate():
    """Envelope of |teeter| per revolution after a 1e-5 rad teeter perturbation: the
    perturbation mostly excites neutral motion, the growing mode takes over after ~25
    revolutions; over revolutions 32..45 (amplitudes < 0.01 rad: linear regime) the
    log-linear slope equals Re(eta) of the Floquet teeter mode, 0.045268 per-rev x Omega0 =
    0.2725 1/s, within 0.5 % (reference: modal_analysis of the same model; the paper
    prints 0.045299 per-rev). Measured: 0.27286 vs 0.27253 (0.12 %; 0.27278 with the step
    solver)."""
    T = load_turbine()
    floquet = max(m.real_per_rev for m in modal_analysis(T, elements=2).modes if m.family == "teeter")
    m = TurbineModel(T, elements=2)
    sim = Simulator(m, step_deg=2.0, perturb={"teeter": 1e-5})
    period = m.period
    env = []
    while sim.t < 45 * period:
        peak = 0.0
        t_end = sim.t + period
        while sim.t < t_end - 1e-9:
            sim.step()
            peak = max(peak, abs(sim.named()["teeter"]))
        env.append(peak)
    env = np.array(env)
    revs = np.arange(len(env))
    sel = revs >= 32
    slope = np.polyfit(revs[sel] * period, np.log(env[sel]), 1)[0]
    assert env.max() < 0.01
    assert slope == pytest.approx(floquet * m.rotor_speed, rel=0.005)
    assert floquet == pytest.approx(0.045299, rel=0.01)
