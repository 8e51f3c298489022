"""Batched evaluation of the rigid-body subsystem (hawt_core/rigid/kane.py).

With a rigid tower every public method of RigidSystem accepts a batch (leading dimensions on
q, u, their rates, t and the root loads).  Reference: the same method evaluated one instant at
a time; the batched results must equal those to round-off (1e-12 relative).
"""
import numpy as np
import pytest

from hawt_core.model import Beam, Gravity, Hub, Nacelle, Rotor, SectionTable, Turbine
from hawt_core.rigid import RigidSystem

RTOL = 1e-12
K = 5


def _blade():
    return Beam(8.42, SectionTable.uniform(mass=67.5772, i1=5.0, i2=1e-4, i3=4.9999,
                                           gj=21.8e3, ei2=4.36e6, ei3=21.8e6), 4)


def _turbine(blades=2, teeter=True, yaw_free=True, gravity=False, general=True):
    """The paper's turbine, or (general=True) one with tilt, precone, undersling, springs,
    dampers, hub mass and optionally gravity."""
    if not general:
        return Turbine("paper", Rotor(blades=blades), Hub(teeter=teeter),
                       Nacelle(yaw_free=yaw_free), _blade())
    return Turbine(
        "general",
        Rotor(speed=4.3, blades=blades, precone=0.07),
        Hub(radius=1.3, undersling=0.35, teeter=teeter, inertia_lateral=80.0,
            inertia_longitudinal=30.0, teeter_stiffness=4.0e4, teeter_damping=2.0e3,
            mass=400.0),
        Nacelle(yaw_inertia=2.0e4, yaw_stiffness=3.0e5, yaw_damping=1.5e4, yaw_to_teeter=3.1,
                shaft_tilt=0.09, yaw_free=yaw_free, mass=900.0),
        _blade(), gravity=Gravity(enabled=gravity, g=9.81))


CONFIGS = {
    "paper": dict(general=False),
    "general_gravity": dict(gravity=True),
    "general_no_gravity": dict(gravity=False),
    "three_blades_rigid_hub": dict(blades=3, teeter=False, gravity=True),
    "yaw_locked": dict(yaw_free=False, gravity=True),
    "yaw_locked_rigid_hub": dict(yaw_free=False, teeter=False, gravity=True),
}


def _close(batch, single):
    single = np.asarray(single)
    batch = np.asarray(batch)
    assert batch.shape == single.shape
    scale = max(np.abs(single).max(initial=0.0), 1e-300)
    np.testing.assert_allclose(batch, single, rtol=RTOL, atol=RTOL * scale)


@pytest.fixture(params=sorted(CONFIGS))
def case(request):
    rs = RigidSystem(_turbine(**CONFIGS[request.param]))
    rng = np.random.default_rng(7)
    nb = rs.n_blades
    data = dict(q=0.2 * rng.standard_normal((K, rs.n_q)),
                qd=0.3 * rng.standard_normal((K, rs.n_q)),
                u=0.3 * rng.standard_normal((K, rs.n_u)),
                ud=0.5 * rng.standard_normal((K, rs.n_u)),
                t=rng.uniform(0.0, 2.0, K),
                F=1e3 * rng.standard_normal((K, nb, 3)),
                M=1e3 * rng.standard_normal((K, nb, 3)))
    return rs, data


def test_batched_methods_equal_per_instant(case):
    """Reference: per-instant evaluation.  root_motion, gravity_in_root, kinematics, dynamics
    and hub_kinetic_energy of a batch of K instants equal the K single-instant results."""
    rs, d = case
    q, qd, u, ud, t, F, M = (d[k] for k in ("q", "qd", "u", "ud", "t", "F", "M"))
    single = [dict(rm=rs.root_motion(q[i], u[i], t[i]),
                   g=rs.gravity_in_root(q[i], t[i]),
                   kin=rs.kinematics(q[i], qd[i], u[i], t[i]),
                   dyn=rs.dynamics(q[i], u[i], ud[i], t[i], F[i], M[i]),
                   ke=rs.hub_kinetic_energy(q[i], u[i], t[i])) for i in range(K)]
    v, w = rs.root_motion(q, u, t)
    _close(v, np.stack([s["rm"][0] for s in single]))
    _close(w, np.stack([s["rm"][1] for s in single]))
    _close(rs.gravity_in_root(q, t), np.stack([s["g"] for s in single]))
    _close(rs.kinematics(q, qd, u, t), np.stack([s["kin"] for s in single]))
    _close(rs.dynamics(q, u, ud, t, F, M), np.stack([s["dyn"] for s in single]))
    ke = rs.hub_kinetic_energy(q, u, t)
    assert np.shape(ke) == (K,)
    _close(ke, np.array([s["ke"] for s in single]))
