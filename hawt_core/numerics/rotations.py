"""Rotations and vector algebra shared by the beams and the rigid bodies (complex-safe: no
abs, comparisons or branches on the values, so complex-step derivatives go through).

Conventions: a rotation matrix's columns are the turned basis in the old one (``rot1(a)``
turns by ``a`` about axis 1, right-handed); Rodrigues parameters ``theta = 2 tan(phi/2) n``
give ``C(theta)`` mapping undeformed (b) components to deformed (B) ones, and ``C^T`` back.
"""
from __future__ import annotations

import numpy as np

__all__ = ["LEVI_CIVITA_9", "cross", "dot", "matvec", "skew", "rot1", "rot2", "rot3",
           "turn_e1_to", "tip_basis", "rot_apply", "rot_T_apply", "q_apply", "atan2"]


def _levi_civita_9() -> np.ndarray:
    eps = np.zeros((3, 3, 3))
    for i, j, k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
        eps[i, j, k], eps[i, k, j] = 1.0, -1.0
    return np.ascontiguousarray(eps.transpose(1, 2, 0).reshape(9, 3))


#: (9, 3) Levi-Civita table: ``cross(a, b)_i = sum_jk eps_ijk a_j b_k``, i.e. the outer
#: product (a_j b_k) flattened over (j, k), times this (one small matmul per cross product)
LEVI_CIVITA_9 = _levi_civita_9()


def cross(a, b):
    """Cross product on the last axis with broadcasting: the outer product contracted with
    the Levi-Civita tensor, one matmul (for 3-vectors several times faster than np.cross;
    the products are multiplied by +-1 and added to exact zeros, so the result equals
    a1 b2 - a2 b1 etc. to the last bit)."""
    p = np.asarray(a)[..., :, None] * np.asarray(b)[..., None, :]
    return p.reshape(p.shape[:-2] + (9,)) @ LEVI_CIVITA_9


def dot(a, b):
    """Dot product on the last axis with broadcasting (einsum: ~3x faster than
    ``(a * b).sum(-1)``, whose reduction over a length-3 axis is slow)."""
    return np.einsum("...i,...i->...", a, b)


def matvec(M, v):
    """Matrix (..., 3, 3) times vector (..., 3) with broadcasting."""
    return (M @ v[..., None])[..., 0]


def skew(a: np.ndarray) -> np.ndarray:
    """Skew matrices of vectors ``a`` (..., 3) -> (..., 3, 3), with ``skew(a) @ b = a x b``."""
    a = np.asarray(a)
    z = np.zeros_like(a[..., 0])
    return np.stack([np.stack([z, -a[..., 2], a[..., 1]], -1),
                     np.stack([a[..., 2], z, -a[..., 0]], -1),
                     np.stack([-a[..., 1], a[..., 0], z], -1)], -2)


def _rotation(axis: int, a) -> np.ndarray:
    """Rotation matrices (a.shape + (3, 3)) for an angle or an array of angles."""
    c = np.cos(a)
    s = np.sin(a)
    R = np.zeros(np.shape(c) + (3, 3), dtype=np.result_type(c, float))
    i, j = ((1, 2), (2, 0), (0, 1))[axis]      # the plane turned, right-handed about axis
    R[..., axis, axis] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rot1(a) -> np.ndarray:
    """Right-handed rotation by ``a`` about axis 1; columns = turned basis in the old one."""
    return _rotation(0, a)


def rot2(a) -> np.ndarray:
    """Right-handed rotation by ``a`` about axis 2; columns = turned basis in the old one."""
    return _rotation(1, a)


def rot3(a) -> np.ndarray:
    """Right-handed rotation by ``a`` about axis 3; columns = turned basis in the old one."""
    return _rotation(2, a)


def turn_e1_to(d) -> np.ndarray:
    """The smallest rotations (..., 3, 3) that turn ``e1`` onto the unit vectors ``d``
    (..., 3): about the axis ``e1 x d``, so a direction normal to both stays put (the
    section frame of a bent reference line, with no twist about it); columns = the turned
    basis in the old one.  ``d = -e1`` is refused (the axis is undefined)."""
    d = np.asarray(d, float)
    c = d[..., 0]
    if np.any(c <= -1.0 + 1e-12):
        raise ValueError("turn_e1_to: a direction opposite to e1 has no smallest rotation")
    k = np.stack([np.zeros_like(c), -d[..., 2], d[..., 1]], -1)   # e1 x d = sin(a) axis
    K = skew(k)
    # Rodrigues: I + K + K^2 / (1 + cos a), exact for |k| = sin a
    return np.eye(3) + K + (K @ K) / (1.0 + c)[..., None, None]


def tip_basis(theta) -> np.ndarray:
    """``C(theta)^T``: columns = the deformed section basis B in the undeformed basis b, for
    Rodrigues parameters theta (..., 3) -> (..., 3, 3) (complex-safe)."""
    th = np.asarray(theta)
    s = (0.25 * dot(th, th))[..., None, None]
    return ((1 - s) * np.eye(3) + skew(th) + 0.5 * th[..., :, None] * th[..., None, :]) / (1 + s)


def rot_T_apply(theta, a):
    """``C(theta)^T a`` (B components -> b components) for Rodrigues parameters (..., 3)."""
    s = 0.25 * dot(theta, theta)
    return (((1 - s)[..., None] * a + cross(theta, a)
             + 0.5 * theta * dot(theta, a)[..., None]) / (1 + s)[..., None])


def rot_apply(theta, a):
    """``C(theta) a`` (b components -> B components)."""
    s = 0.25 * dot(theta, theta)
    return (((1 - s)[..., None] * a - cross(theta, a)
             + 0.5 * theta * dot(theta, a)[..., None]) / (1 + s)[..., None])


def q_apply(theta, a):
    """``Q(theta) a = (I + theta~/2 + theta theta^T/4) a``: Omega = Q(theta) theta_dot-like map
    of the Rodrigues parameters' kinematics."""
    return a + 0.5 * cross(theta, a) + 0.25 * theta * dot(theta, a)[..., None]


def atan2(y, x):
    """atan2(y, x) that accepts complex-step arguments (NumPy's arctan2 does not): the
    quadrant from the real parts, the value from arctan(y / x), exact to first order in
    the imaginary parts (x must not vanish)."""
    y, x = np.asarray(y), np.asarray(x)
    base = np.arctan(y / x)
    turn = np.where(np.real(x) < 0, np.where(np.real(y) >= 0, np.pi, -np.pi), 0.0)
    return base + turn
