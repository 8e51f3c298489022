"""dR/dy of p-version beams (fem/spectral.py) from complex steps of the Gauss-point
integrands: fem/beam_jacobian.py's method on elements of p cells.

Every nonlinear term of a SpectralBeamElements residual is pointwise at its Gauss points
(the integrand there reads the fields interpolated there, the section loads F, M
interpolated there and, in wind, that point's aerodynamic unknowns); the rows are linear in
the integrands (weighted by phi_j or psi_k) plus constant entries (``-int phi_j' psi_k`` on
the equilibrium rows, ``int psi_k phi_j'`` on the strain rows, the root loads).  The
Lagrange bases are partitions of unity, so a complex step of a field at every node (of F, M
at every coefficient) moves every Gauss point's value of it by the same step: the same 18 +
k steps as fem/beam_jacobian.py give every Gauss point's derivatives, and each element's
block follows by the chain rule through the bases and the weights.  At the clamped root the
first element's Gauss points move by ``1 - phi_0(xi)`` under a u or theta step (node 0 is
not an unknown): those derivatives are divided by it (exact).
"""
from __future__ import annotations

import numpy as np

from .beam import BLOCK_SIZE, ROOT_SIZE
from .beam_jacobian import PointwiseBeamJacobian, _FIELDS, _LOADS, field_seeds
from .spectral import SpectralBeamElements


class SpectralPointwiseJacobian(PointwiseBeamJacobian):
    """dR/dy (and dR/dydot) of one SpectralBeamElements beam followed by ``states``
    unknowns per Gauss point (layout of PointwiseBeamJacobian; use :meth:`entries` or
    :meth:`matrix`)."""

    def __init__(self, beam: SpectralBeamElements, states: int = 0):
        self.beam = beam
        Ne, p, Q, G = beam.elements, beam.order, beam.Q, beam.gauss
        N = beam.N
        self.N, self.G, self.k = N, G, int(states)
        self.Ne, self.p, self.Q = Ne, p, Q
        self.n_beam = beam.n
        self.n = beam.n + self.k * N * G
        self.directions = _FIELDS + _LOADS + self.k
        self.seeds = field_seeds(self.n, self.n_beam, N, G, self.k)
        #: the clamped root: how far a u, theta step moves element 0's Gauss points
        self._root_scale = 1.0 - beam._Lq[:, 0]
        nn, nf = 12 * (p + 1), 6 * p
        L = self.local = nn + nf + self.k * Q
        self._nn, self._nf = nn, nf

        def node_idx(g, clamp):
            if g == 0:
                out = np.arange(12)
                if clamp:
                    out = out.copy()
                    out[:6] = -1
                return out
            return ROOT_SIZE + BLOCK_SIZE * (g - 1) + 6 + np.arange(12)

        rows = np.empty((Ne, L), int)
        cols = np.empty((Ne, L), int)
        for e in range(Ne):
            nr = np.concatenate([node_idx(e * p + j, False) for j in range(p + 1)])
            nc = np.concatenate([node_idx(e * p + j, True) for j in range(p + 1)])
            fm = np.concatenate([ROOT_SIZE + BLOCK_SIZE * (e * p + k) + np.arange(6)
                                 for k in range(p)])
            st = (self.n_beam + np.arange(self.k)[:, None] * N * G + e * Q
                  + np.arange(Q)[None, :]).ravel()
            rows[e] = np.concatenate([nr, fm, st])
            cols[e] = np.concatenate([nc, fm, st])
        # the entries that can be nonzero (an element block is dense only where the
        # equations couple: about a quarter of dR/dy's and nine tenths of dR/dydot's L x L
        # entries are structural zeros, which would cost their share of every product and
        # fill the LU factors)
        self._keep = {}
        self._rows, self._cols = {}, {}
        for rates in (False, True):
            keep = (cols[:, None, :] >= 0) & self._structure(rates)[None]
            self._keep[rates] = keep.ravel()
            self._rows[rates] = np.broadcast_to(rows[:, :, None], (Ne, L, L)).ravel()[
                self._keep[rates]]
            self._cols[rates] = np.broadcast_to(cols[:, None, :], (Ne, L, L)).ravel()[
                self._keep[rates]]
        const = np.zeros((Ne, L, L))
        i6 = np.eye(6)
        for j in range(p + 1):
            for k in range(p):
                const[:, 12 * j:12 * j + 6, nn + 6 * k:nn + 6 * k + 6] -= \
                    beam._C[:, j, k, None, None] * i6
                const[:, nn + 6 * k:nn + 6 * k + 6, 12 * j:12 * j + 6] += \
                    beam._D[:, k, j, None, None] * i6
        self._const = const
        # structural damping: the equilibrium rows read the section loads' rates
        # (-int phi_j' mu_hat psi_k, constant)
        self._const_rates = None
        if beam._Cmu is not None:
            cr = np.zeros((Ne, L, L))
            for j in range(p + 1):
                for k in range(p):
                    cr[:, 12 * j:12 * j + 6, nn + 6 * k:nn + 6 * k + 6] -= beam._Cmu[:, j, k]
            self._const_rates = cr
        self._root = (np.arange(6), np.arange(6), -np.ones(6))

    def _structure(self, rates: bool) -> np.ndarray:
        """(L, L) the element block's entries that can be nonzero in dR/dy (``rates``
        False) or dR/dydot.  Local rows: per node [equilibrium 6, kinematics 6], per
        section-load point [strain-displacement 6], the states (state-major); columns: per
        node [u, theta, V, Omega], per point [F, M], the states.  What the equations read:
        equilibrium rows every unknown (with the rates: the node fields', through the
        momenta, the section loads' Vdot, Omegadot and the tip body); kinematics rows the
        node fields (with the rates: udot, thetadot); strain rows u', theta' and theta, F, M
        (no rate); a state row its own Gauss point's states and every field and load of the
        element (its rates: its own states' and the fields').  Verified against the dense
        complex step in tests/test_spectral.py."""
        Q, k, nn, nf, L = self.Q, self.k, self._nn, self._nf, self.local
        node = np.arange(nn) % 12
        eq_rows, kin_rows = np.r_[node < 6, np.zeros(nf + k * Q, bool)], \
            np.r_[node >= 6, np.zeros(nf + k * Q, bool)]
        strain_rows = np.r_[np.zeros(nn, bool), np.ones(nf, bool), np.zeros(k * Q, bool)]
        state = np.r_[np.zeros(nn + nf, bool), np.ones(k * Q, bool)]
        node_cols = np.r_[np.ones(nn, bool), np.zeros(nf + k * Q, bool)]
        u_theta = np.r_[node < 6, np.zeros(nf + k * Q, bool)]
        load_cols = np.r_[np.zeros(nn, bool), np.ones(nf, bool), np.zeros(k * Q, bool)]
        point = np.full(L, -1)
        point[nn + nf:] = np.tile(np.arange(Q), k)            # the states' Gauss points
        same_point = state[:, None] & state[None, :] & (point[:, None] == point[None, :])
        M = np.zeros((L, L), bool)
        if rates:
            M |= eq_rows[:, None] & node_cols[None, :]
            if self.beam._Cmu is not None:          # damped: the loads' rates
                M |= eq_rows[:, None] & load_cols[None, :]
            M |= kin_rows[:, None] & u_theta[None, :]
            M |= state[:, None] & node_cols[None, :]
        else:
            M |= eq_rows[:, None]
            M |= kin_rows[:, None] & node_cols[None, :]
            M |= strain_rows[:, None] & (u_theta | load_cols)[None, :]
            M |= state[:, None] & (node_cols | load_cols)[None, :]
        return M | same_point

    def values(self, capture: dict, state_rows, h: float, blocks: int, rates: bool = False):
        """As PointwiseBeamJacobian.values, for the p-version's elements."""
        beam = self.beam
        Ne, p, Q, D, k, nb = self.Ne, self.p, self.Q, self.directions, self.k, blocks
        nn, nf, L = self._nn, self._nf, self.local
        A = capture["integrand"].imag.reshape(Ne, Q, D, nb, 18).transpose(0, 1, 3, 4, 2) / h
        A[0, :, :, :, 0:6] /= self._root_scale[:, None, None, None]
        WL, WP, Lq, Pq = beam._WL, beam._WP, beam._Lq, beam._Pq
        V = np.zeros((Ne, nb, L, L))
        Fc = slice(_FIELDS, _FIELDS + _LOADS)
        An, As = A[..., 0:12, :], A[..., 12:18, :]
        V[:, :, :nn, :nn] = np.einsum("ejq,qi,eqbrd->ebjrid", WL, Lq,
                                      An[..., :_FIELDS]).reshape(Ne, nb, nn, nn)
        V[:, :, :nn, nn:nn + nf] = np.einsum("ejq,qm,eqbrd->ebjrmd", WL, Pq,
                                             An[..., Fc]).reshape(Ne, nb, nn, nf)
        V[:, :, nn:nn + nf, :nn] = -np.einsum("ekq,qi,eqbrd->ebkrid", WP, Lq,
                                              As[..., :_FIELDS]).reshape(Ne, nb, nf, nn)
        V[:, :, nn:nn + nf, nn:nn + nf] = -np.einsum("ekq,qm,eqbrd->ebkrmd", WP, Pq,
                                                     As[..., Fc]).reshape(Ne, nb, nf, nf)
        if not rates:
            V += self._const[:, None]
        elif self._const_rates is not None:
            V += self._const_rates[:, None]
        if capture.get("tip") is not None:
            T = capture["tip"].imag.reshape(D, nb, 6)[:_FIELDS].transpose(1, 2, 0) / h
            V[Ne - 1, :, 12 * p:12 * p + 6, 12 * p:12 * p + 12] += T
        if k:
            S = slice(nn + nf, L)
            Ax = A[..., _FIELDS + _LOADS:]                              # (Ne, Q, nb, 18, k)
            # structural rows w.r.t. each Gauss point's states (state-major columns)
            V[:, :, :nn, S] = np.einsum("ejq,eqbrs->ebjrsq", WL, Ax[..., 0:12, :]).reshape(
                Ne, nb, nn, k * Q)
            V[:, :, nn:nn + nf, S] = -np.einsum("ekq,eqbrs->ebkrsq", WP,
                                                Ax[..., 12:18, :]).reshape(Ne, nb, nf, k * Q)
            # the state rows at each Gauss point w.r.t. its inputs
            Bq = state_rows.imag.reshape(D, nb, k, Ne, Q).transpose(3, 4, 1, 2, 0) / h
            Bq[0, :, :, :, 0:6] /= self._root_scale[:, None, None, None]  # (Ne, Q, nb, k, D)
            V[:, :, S, :nn] = np.einsum("eqbsd,qi->ebsqid", Bq[..., :_FIELDS], Lq).reshape(
                Ne, nb, k * Q, nn)
            V[:, :, S, nn:nn + nf] = np.einsum("eqbsd,qm->ebsqmd", Bq[..., Fc], Pq).reshape(
                Ne, nb, k * Q, nf)
            own = Bq[..., _FIELDS + _LOADS:]                                # (Ne, Q, nb, k, k)
            blk = np.zeros((Ne, nb, k, Q, k, Q))
            idx = np.arange(Q)
            blk[:, :, :, idx, :, idx] = own.transpose(1, 0, 2, 3, 4)
            V[:, :, S, S] = blk.reshape(Ne, nb, k * Q, k * Q)
        vals = V.transpose(1, 0, 2, 3).reshape(nb, -1)[:, self._keep[rates]]
        rows, cols = self._rows[rates], self._cols[rates]
        if rates:
            return rows, cols, vals
        r0, c0, v0 = self._root
        return (np.concatenate([rows, r0]), np.concatenate([cols, c0]),
                np.concatenate([vals, np.broadcast_to(v0, (nb, 6))], axis=1))
