"""dR/dy of beams (fem/beam.py) from complex steps of the Gauss-point integrands.

Every nonlinear term of a BeamElements residual is *pointwise*: the integrand at a Gauss
point reads only the fields interpolated there (u, theta, V, Omega), its element's section
loads F, M and, for a blade in wind, the aerodynamic unknowns of that point; the element
constants h/2 [kappa x F, kappa x M + (t + gamma) x F] read only F, M; the tip body only the
tip node.  The rows are linear in these pieces (hat-weighted sums, differences, +-F, M).
So ONE complex step per field, applied to that field at every node (or element, or Gauss
point) at once, gives the derivative of every Gauss point's integrand with respect to its
own inputs: 18 + k steps (k the aerodynamic unknowns per Gauss point) instead of the 54 or
more colours of the block-tridiagonal pattern (numerics/jacobian.py), whatever N.  The
element blocks then follow by the chain rule through the interpolation (1 - eta, eta) and
the hat weights, one small einsum.  Values equal the coloured complex step to round-off
(tests/test_beam_jacobian.py).

At the root the displacement and rotation are clamped (not unknowns): a step of u or theta
at every node moves the first element's Gauss points by eta only, so that element's
derivatives with respect to u, theta are divided by eta (exact: the complex step is linear
in the step).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..numerics.jacobian import STEP
from .beam import BLOCK_SIZE, ROOT_SIZE, BeamElements

#: nodal fields [u, theta, V, Omega] (12), then the element loads [F, M] (6)
_FIELDS, _LOADS = 12, 6
#: the element's row groups: (weight index in _wr, local rows, integrand components): left
#: node and right node (equilibrium, kinematics), strain-displacement
_ROW_GROUPS = ((0, (0, 12), (0, 12)), (1, (12, 24), (0, 12)), (2, (24, 30), (12, 18)))


def field_seeds(n: int, n_beam: int, N: int, G: int, k: int) -> np.ndarray:
    """(18 + k, n) complex-step seeds of the Gauss-point Jacobians: field f of every node
    (the root's V, Omega too: its u, theta are clamped), the section loads of every cell,
    and state j at every Gauss point (layout of BeamElements / SpectralBeamElements with
    N cells of G points and k states per point after the n_beam beam unknowns)."""
    blocks = ROOT_SIZE + BLOCK_SIZE * np.arange(N)
    seeds = np.zeros((_FIELDS + _LOADS + k, n))
    for f in range(_FIELDS):
        seeds[f, blocks + 6 + f] = 1.0
        if f >= 6:                      # the root's V, Omega are unknowns (u, theta: 0)
            seeds[f, f] = 1.0
    for m in range(_LOADS):
        seeds[_FIELDS + m, blocks + m] = 1.0
    for j in range(k):
        seeds[_FIELDS + _LOADS + j, n_beam + j * N * G + np.arange(N * G)] = 1.0
    return seeds


class PointwiseBeamJacobian:
    """dR/dy of ``beam``'s rows and unknowns, followed by ``states`` unknowns per Gauss point
    laid out state-major (state j of Gauss point g of element e at ``n_beam + (j N + e) G +
    g``, as RotorAerodynamics; their rows likewise), from the pieces BeamElements.residual
    captures (``capture=``) at the ``directions`` seeded points.

    Use: evaluate the residual at ``y + 1j * h * seeds`` (``seeds`` (D, n), D =
    ``directions``) with a capture dict; :meth:`values` turns the captured pieces (and the
    state rows) into the (rows, cols, values) of one beam block per beam, duplicates to be
    summed (a node's rows collect both neighbouring elements)."""

    def __init__(self, beam: BeamElements, states: int = 0):
        self.beam = beam
        N, G = beam.N, len(beam.eta)
        self.N, self.G, self.k = N, G, int(states)
        self.n_beam = beam.n
        self.n = beam.n + self.k * N * G
        self.directions = _FIELDS + _LOADS + self.k
        self.seeds = field_seeds(self.n, self.n_beam, N, G, self.k)
        eta = beam.eta
        #: (G, 3) column weights: left node, right node, element constant
        self._phi = np.stack([1 - eta, eta, np.ones(G)], -1)
        #: (N, 3, G) row weights: left node, right node (hat), strain rows (-(sum))
        self._wr = np.stack([beam.wa, beam.wb, -(beam.wa + beam.wb)], 1)
        # local rows [left node 12 | right node 12 | strain 6 | states (j, g)] and columns
        # [left node 12 | right node 12 | F, M 6 | states (j, g)] of each element -> global
        L = 30 + self.k * G
        self.local = L
        rows = np.empty((N, L), int)
        cols = np.empty((N, L), int)
        def node(p):    # node p: its rows [equilibrium, kinematics], unknowns [u, theta, V, Omega]
            return np.arange(12) if p == 0 else ROOT_SIZE + BLOCK_SIZE * (p - 1) + 6 + np.arange(12)
        states_of = lambda e: (self.n_beam + (np.arange(self.k)[:, None] * N + e) * G
                               + np.arange(G)[None, :]).ravel()
        for e in range(N):
            own = ROOT_SIZE + BLOCK_SIZE * e + np.arange(6)
            left_cols = node(e).copy()
            if e == 0:
                left_cols[:6] = -1          # clamped u, theta
            rows[e] = np.concatenate([node(e), node(e + 1), own, states_of(e)])
            cols[e] = np.concatenate([left_cols, node(e + 1), own, states_of(e)])
        keep = np.broadcast_to(cols[:, None, :] >= 0, (N, L, L))
        self._keep = keep.ravel()
        self._rows = np.broadcast_to(rows[:, :, None], (N, L, L)).ravel()[self._keep]
        self._cols = np.broadcast_to(cols[:, None, :], (N, L, L)).ravel()[self._keep]
        # constant entries: the root loads' -1 in the root equilibrium rows, +-1 of the
        # element loads in both ends' equilibrium rows, the u, theta differences in the
        # strain rows
        const = np.zeros((N, L, L))
        i6 = np.eye(6)
        const[:, 0:6, 24:30] += i6
        const[:, 12:18, 24:30] -= i6
        const[:, 24:30, 0:6] -= i6
        const[:, 24:30, 12:18] += i6
        self._const = const
        # structural damping: both ends' equilibrium rows read the loads' rates (+-mu_hat)
        self._const_rates = None
        if beam._muhatT is not None:
            cr = np.zeros((N, L, L))
            mu_hat = beam._muhatT.transpose(0, 2, 1)
            cr[:, 0:6, 24:30] += mu_hat
            cr[:, 12:18, 24:30] -= mu_hat
            self._const_rates = cr
        self._root = (np.arange(6), np.arange(6), -np.ones(6))

    def values(self, capture: dict, state_rows, h: float, blocks: int, rates: bool = False):
        """(rows, cols, values) of ``blocks`` beams (values (blocks, nnz) in the order of
        ``rows``, ``cols`` (nnz,), local to one beam) from the ``capture`` of the residual
        at the seeded points (batch D * blocks, direction-major) with complex step ``h``,
        and the state rows' output (D * blocks, k N G) (None without states).

        ``rates``: the seeds were applied to the rates (ydot): dR/dydot, which reads the
        rates of the same fields at the same points (hat-interpolated udot, thetadot,
        Vdot, Omegadot, the states' rates; the tip body's Vdot, Omegadot) and has none of
        dR/dy's constant entries (the element loads, the differences, the root loads)."""
        N, G, D, k, nb = self.N, self.G, self.directions, self.k, blocks
        # d(integrand at (e, g))/d(its inputs): (N, G, nb, 18, D)
        A = capture["integrand"].imag.reshape(N, G, D, nb, 18).transpose(0, 1, 3, 4, 2) / h
        A[0, :, :, :, 0:6] /= self.beam.eta[:, None, None, None]
        wr, phi = self._wr, self._phi
        V = np.zeros((N, nb, self.local, self.local))
        # structural rows w.r.t. nodal fields and element loads
        S4 = np.einsum("erg,gc,egbid->ebrcid", wr, phi, A[..., :_FIELDS + _LOADS])
        for r, (r0, r1), (i0, i1) in _ROW_GROUPS:
            V[:, :, r0:r1, 0:12] = S4[:, :, r, 0, i0:i1, :_FIELDS]
            V[:, :, r0:r1, 12:24] = S4[:, :, r, 1, i0:i1, :_FIELDS]
            V[:, :, r0:r1, 24:30] = S4[:, :, r, 2, i0:i1, _FIELDS:]
        # element constants: d(h/2 [k x F, k x M + (t + g) x F])/d(F, M) on both ends
        C6 = capture["element"].imag.reshape(N, D, nb, 6)[:, _FIELDS:_FIELDS + _LOADS] / h
        C6 = C6.transpose(0, 2, 3, 1)                                   # (N, nb, 6, 6)
        V[:, :, 0:6, 24:30] += C6
        V[:, :, 12:18, 24:30] += C6
        if not rates:
            V += self._const[:, None]
        elif self._const_rates is not None:
            V += self._const_rates[:, None]
        if capture.get("tip") is not None:          # the tip body: the last node's rows
            T = capture["tip"].imag.reshape(D, nb, 6)[:_FIELDS].transpose(1, 2, 0) / h
            V[N - 1, :, 12:18, 12:24] += T
        if k:
            # structural rows w.r.t. the states of each Gauss point (no sum over points)
            X = np.einsum("erg,egbid->ebrigd", wr, A[..., _FIELDS + _LOADS:])
            for r, (r0, r1), (i0, i1) in _ROW_GROUPS:
                V[:, :, r0:r1, 30:] = X[:, :, r, i0:i1].transpose(0, 1, 2, 4, 3).reshape(
                    N, nb, i1 - i0, k * G)
            # the state rows (state-major (j, e, g)) at each Gauss point w.r.t. its inputs
            B = state_rows.imag.reshape(D, nb, k, N, G).transpose(3, 4, 1, 2, 0) / h
            B[0, :, :, :, 0:6] /= self.beam.eta[:, None, None, None]
            Bt = B.transpose(0, 2, 3, 1, 4)                         # (N, nb, k, G, D)
            rs = slice(30, 30 + k * G)
            for c, (c0, c1) in enumerate(((0, 12), (12, 24))):
                V[:, :, rs, c0:c1] = (Bt[..., :_FIELDS] * phi[:, c][None, None, None, :, None]
                                      ).reshape(N, nb, k * G, _FIELDS)
            V[:, :, rs, 24:30] = Bt[..., _FIELDS:_FIELDS + _LOADS].reshape(N, nb, k * G, _LOADS)
            own = Bt[..., _FIELDS + _LOADS:]                        # (N, nb, k, G, k)
            idx = np.arange(G)
            blk = np.zeros((N, nb, k, G, k, G))
            blk[:, :, :, idx, :, idx] = own.transpose(3, 0, 1, 2, 4)
            V[:, :, rs, rs] = blk.reshape(N, nb, k * G, k * G)
        vals = V.transpose(1, 0, 2, 3).reshape(nb, -1)[:, self._keep]
        if rates:
            return self._rows, self._cols, vals
        r0, c0, v0 = self._root
        return (np.concatenate([self._rows, r0]), np.concatenate([self._cols, c0]),
                np.concatenate([vals, np.broadcast_to(v0, (nb, 6))], axis=1))

    def entries(self, fun, ydot, y, rates: bool = False):
        """(rows, cols, values (nblk, nnz)) of dR/dy (or with ``rates`` dR/dydot) of nblk
        beams at ``ydot``, ``y`` (nblk, n), whose residual is ``fun(Ydot, Y, capture) ->
        (D * nblk, n)`` (batch direction-major; BeamElements.residual's capture passed on):
        all the steps of all beams in one call (see :meth:`values`)."""
        ydot, y = np.atleast_2d(ydot), np.atleast_2d(y)
        nblk, D = y.shape[0], self.directions
        seeds = np.repeat(self.seeds, nblk, axis=0) * (1j * STEP)       # (D*nblk, n)
        Yd, Y = np.tile(ydot, (D, 1)), np.tile(y, (D, 1))
        cap = {}
        r = fun(Yd + seeds, Y, cap) if rates else fun(Yd, Y + seeds, cap)
        return self.values(cap, r[:, self.n_beam:] if self.k else None, STEP, nblk,
                           rates=rates)

    def matrix(self, fun, ydot, y, rates: bool = False) -> sp.csc_matrix:
        """dR/dy (or with ``rates`` dR/dydot) (n, n) of ONE beam (:meth:`entries`) at
        ``ydot``, ``y`` (n,)."""
        rows, cols, vals = self.entries(fun, np.asarray(ydot, float), np.asarray(y, float),
                                        rates)
        return sp.csc_matrix((vals[0], (rows, cols)), shape=(self.n, self.n))
