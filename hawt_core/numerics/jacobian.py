"""Exact sparse Jacobians by the complex-step method with column colouring.

For a complex-safe residual ``R`` (analytic in its arguments), ``Im R(y + i h e_j) / h`` equals
``dR/dy_j`` to round-off for any tiny ``h`` (no subtractive cancellation). Columns that share no
row in the sparsity pattern are perturbed together (one residual call per colour).
"""
from __future__ import annotations

import hashlib
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp

STEP = 1e-30


def block_tridiagonal_pattern(sizes) -> sp.csr_matrix:
    """Boolean pattern with dense blocks on the block diagonal and its two neighbours."""
    sizes = list(sizes)
    off = np.concatenate([[0], np.cumsum(sizes)])
    nb = len(sizes)
    rows, cols = [], []
    for i in range(nb):
        for j in range(max(0, i - 1), min(nb, i + 2)):
            r = np.arange(off[i], off[i + 1])
            c = np.arange(off[j], off[j + 1])
            rr, cc = np.meshgrid(r, c, indexing="ij")
            rows.append(rr.ravel())
            cols.append(cc.ravel())
    n = off[-1]
    data = np.ones(sum(len(r) for r in rows), bool)
    return sp.csr_matrix((data, (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))


def beam_station_pattern(sizes, gauss_points: int, states: int) -> sp.csr_matrix:
    """Pattern of a beam (block sizes ``sizes``: the root block, then one per element; see
    block_tridiagonal_pattern) followed by ``states`` unknowns at each of its elements'
    ``gauss_points`` Gauss points, laid out state-major (state j of Gauss point g of element
    e at ``n_beam + (j N + e) G + g``): the states of element e reach the rows of its two
    nodes' blocks (e, e + 1) and their own rows (all the states of that Gauss point), which
    read the two nodes' blocks."""
    sizes = list(sizes)
    beam = block_tridiagonal_pattern(sizes)
    N, G, k = len(sizes) - 1, int(gauss_points), int(states)
    if k == 0:
        return beam
    starts = np.concatenate([[0], np.cumsum(sizes)])
    n_beam = int(starts[-1])
    rows, cols = [], []
    for e in range(N):
        nodes = np.arange(starts[e], starts[e + 2])
        for g in range(G):
            own = n_beam + N * G * np.arange(k) + e * G + g
            for r, c in ((nodes, own), (own, nodes), (own, own)):
                rr, cc = np.meshgrid(r, c, indexing="ij")
                rows.append(rr.ravel()), cols.append(cc.ravel())
    n = n_beam + N * G * k
    extra = sp.csr_matrix((np.ones(sum(len(r) for r in rows), bool),
                           (np.concatenate(rows), np.concatenate(cols))), shape=(n, n))
    return (sp.block_diag([beam, sp.csr_matrix((N * G * k, N * G * k), dtype=bool)],
                          format="csr") + extra).astype(bool)


def greedy_colouring(pattern: sp.spmatrix) -> np.ndarray:
    """Colour the columns so that no two columns of one colour share a row."""
    pat = sp.csc_matrix(pattern, dtype=bool)
    pat_r = sp.csr_matrix(pattern, dtype=bool)
    n = pat.shape[1]
    colour = -np.ones(n, int)
    for j in range(n):
        rows = pat.indices[pat.indptr[j]:pat.indptr[j + 1]]
        neigh = np.unique(np.concatenate([pat_r.indices[pat_r.indptr[r]:pat_r.indptr[r + 1]]
                                          for r in rows])) if len(rows) else np.array([], int)
        used = set(colour[neigh][colour[neigh] >= 0].tolist())
        c = 0
        while c in used:
            c += 1
        colour[j] = c
    return colour


#: Colourings of the patterns seen last (models are rebuilt with the same mesh many times:
#: an operating-point sweep builds one per pitch it tries): pattern key -> colours.
_COLOURINGS: "OrderedDict[tuple, np.ndarray]" = OrderedDict()
_COLOURINGS_KEPT = 16


def _colouring(pattern: sp.csc_matrix) -> np.ndarray:
    """greedy_colouring of a canonical (sorted, summed) CSC pattern, remembered."""
    digest = hashlib.sha1(pattern.indptr.tobytes())
    digest.update(pattern.indices.tobytes())
    key = (pattern.shape, pattern.nnz, digest.digest())
    colour = _COLOURINGS.get(key)
    if colour is None:
        colour = greedy_colouring(pattern)
        colour.setflags(write=False)
        _COLOURINGS[key] = colour
        if len(_COLOURINGS) > _COLOURINGS_KEPT:
            _COLOURINGS.popitem(last=False)
    else:
        _COLOURINGS.move_to_end(key)
    return colour


class ColouredJacobian:
    """Sparse complex-step Jacobian of ``fun(x) -> (m,)`` with a fixed sparsity ``pattern``."""

    def __init__(self, pattern: sp.spmatrix):
        self.pattern = sp.csc_matrix(pattern, dtype=bool)
        self.pattern.sum_duplicates()
        self.pattern.sort_indices()
        self.colour = _colouring(self.pattern)
        self.n_colours = int(self.colour.max()) + 1 if len(self.colour) else 0
        coo = self.pattern.tocoo()
        self._rows, self._cols = coo.row, coo.col
        self._col_colour = self.colour[coo.col]
        self.seeds = np.zeros((self.n_colours, self.pattern.shape[1]))
        self.seeds[self.colour, np.arange(self.pattern.shape[1])] = 1.0

    def __call__(self, fun, x) -> sp.csc_matrix:
        x = np.asarray(x, dtype=float)
        m = self.pattern.shape[0]
        comp = np.empty((self.n_colours, m))
        for c in range(self.n_colours):
            comp[c] = fun(x + 1j * STEP * self.seeds[c]).imag / STEP
        vals = comp[self._col_colour, self._rows]
        return sp.csc_matrix((vals, (self._rows, self._cols)), shape=self.pattern.shape)


    def batched(self, fun_batch, x) -> sp.csc_matrix:
        """Same as calling the instance, with ``fun_batch(X) -> (C, m)`` evaluating all the
        colours' perturbed points ``X`` (C, n) in one vectorized call."""
        x = np.asarray(x, dtype=float)
        comp = fun_batch(x[None, :] + 1j * STEP * self.seeds).imag / STEP
        vals = comp[self._col_colour, self._rows]
        return sp.csc_matrix((vals, (self._rows, self._cols)), shape=self.pattern.shape)


def dense_complex_step(fun, x) -> np.ndarray:
    """Dense complex-step Jacobian (reference implementation for tests)."""
    x = np.asarray(x, dtype=float)
    cols = [fun(x + 1j * STEP * e).imag / STEP for e in np.eye(len(x))]
    return np.stack(cols, -1)
