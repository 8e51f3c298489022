"""Multi-blade coordinates (the Coleman transform) of the turbine's unknowns and equations.

Blade b (b = 0..Nb-1) stands at the azimuth ``psi_b = Omega0 t + 2 pi b / Nb`` (blade 0 up at
t = 0, blade b ahead of it in the sense of rotation; hawt_core.rigid.kane).  Every blade
unknown (the same local index in every blade block) is written in fixed-frame (multi-blade)
coordinates::

    x_b = x_0 + sum_{k=1..K} (x_ck cos(k psi_b) + x_sk sin(k psi_b)) [+ x_d (-1)^b]

with ``K = (Nb - 1) // 2`` cyclic pairs and the differential coordinate ``x_d`` for an even
blade count (Bir, NREL/TP-500-42553, 2008: MBC3 for three blades; Johnson, *Helicopter
Theory*, sec. 8.4, for any count).  In matrix form ``x = T(t) z``: the rigid and tower
unknowns are kept, blade slot j of ``z`` holds coordinate j (collective, cos 1, sin 1, cos 2,
..., differential).  The residual rows of blade b are combined with ``T(t)^-1`` in the same
way, so ``E x' = A x`` becomes

    E_z z' = A_z z,   E_z = T^-1 E T,   A_z = T^-1 (A T - E dT/dt).

For an isotropic rotor (identical, equally spaced blades on a rigid hub) whose steady state is
constant in the rotating frame (no gravity), E_z and A_z are constant for Nb >= 3: the
periodic system becomes time-invariant, one eigenproblem gives every exponent, and the
eigenvalues are the fixed-frame frequencies.  Otherwise (gravity, an asymmetric rotor) the
coefficients keep the period T/Nb (odd Nb) or 2T/Nb (even Nb: the differential coordinate
changes sign when the blades are relabelled).

Whirl of a cyclic pair (fixed-frame amplitudes ``z_c``, ``z_s`` of ``e^{i omega t}``,
omega > 0): the forward-whirl part ``a_f = (z_c + i z_s) / 2`` is a blade-deflection pattern
turning with the rotor at omega (``omega_fixed = omega_rotating + k Omega0``), the
backward-whirl part ``a_b = (z_c - i z_s) / 2`` one turning against it
(``omega_fixed = omega_rotating - k Omega0``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.sparse as sp

from .floquet import LinearPeriodicDAE, dominant_harmonic

#: Names of the multi-blade coordinates: "collective", "cos1", "sin1", ..., "differential".
WHIRLS = ("collective", "forward", "backward", "differential")


def coordinate_names(blades: int) -> list:
    """The multi-blade coordinates of ``blades`` blades, in slot order."""
    names = ["collective"]
    for k in range(1, (blades - 1) // 2 + 1):
        names += [f"cos{k}", f"sin{k}"]
    if blades % 2 == 0:
        names.append("differential")
    return names


def _orders(blades: int) -> np.ndarray:
    """Harmonic order k of every coordinate (0 collective, Nb/2 differential)."""
    out = [0]
    for k in range(1, (blades - 1) // 2 + 1):
        out += [k, k]
    if blades % 2 == 0:
        out.append(blades // 2)
    return np.array(out)


class MultiBladeTransform:
    """The Coleman transform of a TurbineModel with Nb >= 3 identical blades.

    ``matrix(t)`` is ``T(t)`` (n x n, sparse, x = T z), ``rate(t)`` its time derivative,
    ``inverse(t)`` its inverse; :meth:`dae` transforms a LinearPeriodicDAE of the model.
    ``period`` is the period of the transformed coefficients (T/Nb or 2T/Nb)."""

    def __init__(self, model):
        nb = int(model.n_blades)
        if nb < 3:
            raise ValueError(f"multi-blade coordinates: {nb} blades; they need at least 3")
        self.model = model
        self.blades = nb
        self.omega = float(model.rotor_speed)
        if not self.omega > 0:
            raise ValueError("multi-blade coordinates: need a spinning rotor (rotor speed > 0)")
        self.n = model.n
        self.names = coordinate_names(nb)
        self.orders = _orders(nb)
        self.n_beam = model.blade_size
        self.offset = model.layout.blade_offset(0)
        self.rotor_period = 2.0 * math.pi / self.omega
        self.period = self.rotor_period / nb * (2 if nb % 2 == 0 else 1)
        self._n_after = self.n - self.offset - nb * self.n_beam

    # ------------------------------------------------------------------ blade matrices
    def blade_matrix(self, t) -> np.ndarray:
        """C(t) (Nb, Nb): C[b, j] = c_j(psi_b), the value of coordinate j's basis function
        on blade b; ``x_blades = C z_coordinates``."""
        return self._basis(t, 0)

    def blade_rate(self, t) -> np.ndarray:
        """dC/dt (Nb, Nb)."""
        return self._basis(t, 1)

    def blade_inverse(self, t) -> np.ndarray:
        """C(t)^-1 (Nb, Nb): ``z = C^-1 x_blades`` (1/Nb times 1, 2 cos, 2 sin, (-1)^b)."""
        nb = self.blades
        C = self._basis(t, 0)
        w = np.where(self.orders == 0, 1.0, 2.0)
        if nb % 2 == 0:
            w[-1] = 1.0
        return (C * w[None, :]).T / nb

    def _basis(self, t, derivative: int) -> np.ndarray:
        nb = self.blades
        psi = self.omega * float(t) + 2.0 * math.pi * np.arange(nb) / nb
        out = np.zeros((nb, nb))
        out[:, 0] = 1.0 if derivative == 0 else 0.0
        j = 1
        for k in range(1, (nb - 1) // 2 + 1):
            if derivative == 0:
                out[:, j], out[:, j + 1] = np.cos(k * psi), np.sin(k * psi)
            else:
                w = k * self.omega
                out[:, j], out[:, j + 1] = -w * np.sin(k * psi), w * np.cos(k * psi)
            j += 2
        if nb % 2 == 0:
            out[:, j] = (-1.0) ** np.arange(nb) if derivative == 0 else 0.0
        return out

    # ------------------------------------------------------------------ state matrices
    def _embed(self, C: np.ndarray, diagonal: float) -> sp.csr_matrix:
        blocks = [sp.identity(self.offset) * diagonal,
                  sp.kron(sp.csr_matrix(C), sp.identity(self.n_beam))]
        if self._n_after:
            blocks.append(sp.identity(self._n_after) * diagonal)
        return sp.block_diag(blocks, format="csr")

    def matrix(self, t) -> sp.csr_matrix:
        """T(t) (n, n): x = T(t) z."""
        return self._embed(self.blade_matrix(t), 1.0)

    def rate(self, t) -> sp.csr_matrix:
        """dT/dt (n, n) (zero outside the blade blocks)."""
        return self._embed(self.blade_rate(t), 0.0)

    def inverse(self, t) -> sp.csr_matrix:
        """T(t)^-1 (n, n)."""
        return self._embed(self.blade_inverse(t), 1.0)

    def dae(self, rotating: LinearPeriodicDAE) -> LinearPeriodicDAE:
        """The system in multi-blade coordinates, ``E_z(t) z' = A_z(t) z`` with the period
        :attr:`period` (constant coefficients for an isotropic rotor without gravity)."""
        cache: dict = {}

        def pair(t):
            t = float(t)
            if t not in cache:
                if len(cache) > 64:
                    cache.clear()
                E, A = rotating.E(t), rotating.A(t)
                Tm, Ti = self.matrix(t), self.inverse(t)
                Ez = (Ti @ E @ Tm).tocsc()
                Az = (Ti @ (A @ Tm - E @ self.rate(t))).tocsc()
                Ez.eliminate_zeros()
                Az.eliminate_zeros()
                cache[t] = (Ez, Az)
            return cache[t]

        # the differential mask is unchanged: a blade slot's unknowns keep their kind
        return LinearPeriodicDAE(lambda t: pair(t)[0], lambda t: pair(t)[1], self.period,
                                 rotating.differential)

    # ------------------------------------------------------------------ modes
    def blade_groups(self, rows) -> Optional[np.ndarray]:
        """(G, Nb) positions in ``rows`` of the blade unknowns grouped by local index (blade
        0..Nb-1 of every local unknown present), or None if some blade's copy is missing."""
        rows = np.asarray(rows, int)
        pos = {int(r): i for i, r in enumerate(rows)}
        local = rows - self.offset
        blade_rows = rows[(local >= 0) & (local < self.blades * self.n_beam)]
        locs = np.unique((blade_rows - self.offset) % self.n_beam)
        out = np.empty((locs.size, self.blades), int)
        for b in range(self.blades):
            r = self.offset + b * self.n_beam + locs
            if any(int(x) not in pos for x in r):
                return None
            out[:, b] = [pos[int(x)] for x in r]
        return out

    def _mix(self, P: np.ndarray, times, groups: np.ndarray, inverse: bool) -> np.ndarray:
        Z = np.array(P, dtype=complex, copy=True)
        mats = [self.blade_inverse(t) if inverse else self.blade_matrix(t) for t in times]
        Cm = np.array(mats)                                     # (M, Nb, Nb)
        blades = np.asarray(P)[:, groups]                       # (M, G, Nb, ...)
        Z[:, groups] = np.einsum("mjb,mgb...->mgj...", Cm, blades)
        return Z

    def to_fixed(self, P: np.ndarray, times, groups: np.ndarray) -> np.ndarray:
        """Multi-blade coordinates of rotating-frame samples ``P`` (M, rows, ...) at ``times``
        (M,): the blade rows of every group (``blade_groups``) are replaced by the coordinates
        (slot j of a group holds coordinate j); other rows are copied."""
        return self._mix(P, times, groups, inverse=True)

    def to_rotating(self, Q: np.ndarray, times, groups: np.ndarray) -> np.ndarray:
        """The inverse of :meth:`to_fixed`: blade values from multi-blade coordinates."""
        return self._mix(Q, times, groups, inverse=False)


@dataclass
class FixedFrameMode:
    """Fixed-frame view of one mode: exponent [rad/s] with the dominant fixed-frame harmonic,
    whirl (collective, forward, backward, differential), the order k of the dominant cyclic
    pair (0 for collective, Nb/2 for differential) and the per-blade energy shares of each
    whirl class."""

    exponent: complex
    whirl: str
    order: int
    shares: dict


def fixed_frame_modes(transform: MultiBladeTransform, fl, specs: dict) -> dict:
    """{column: FixedFrameMode} for modes of a FloquetResult ``fl`` (rotating frame; any
    method).  ``specs``: {column: (rows, weights, whirl_rows, whirl_weights)}: the rows (and
    weights, metres of motion) whose dominant fixed-frame harmonic gives the frequency, and
    those whose blade part gives the whirl; blade rows must come with every blade's copy.

    The periodic eigenvector p(t) (rotating frame) becomes ``q(t) = C(t)^-1 p(t)`` in
    multi-blade coordinates, ``x = q(t) e^{eta t}``; the dominant harmonic k of q (weighted:
    per-blade energies, the cyclic coordinates at half weight) gives the fixed-frame exponent
    ``eta + i k Omega0``, and the mean of ``q(t) e^{-i k Omega0 t}`` the fixed-frame amplitudes
    whose blade part gives the whirl (per-blade energies of the collective, forward,
    backward and differential parts; the largest names it)."""
    pos = {int(r): j for j, r in enumerate(fl.sample_rows)}
    nb = transform.blades
    orders = transform.orders
    coord_w = np.where(orders == 0, 1.0, 0.5)
    if nb % 2 == 0:
        coord_w[-1] = 1.0
    times = fl.sample_times
    M = len(times)
    kk = np.fft.fftfreq(M, 1.0 / M).astype(int)
    w0 = fl.omega
    out = {}
    for c, (rows, weights, wrows, wweights) in specs.items():
        rows = list(rows) + [r for r in wrows if r not in set(rows)]
        wmap = dict(zip(map(int, wrows), wweights))
        fmap = dict(zip(map(int, specs[c][0]), specs[c][1]))
        rows = np.array(rows, int)
        sel = np.array([pos[int(r)] for r in rows])
        groups = transform.blade_groups(rows)
        if groups is None:
            raise ValueError("fixed-frame modes: the rows lack some blade's copy")
        P = fl.periodic_sample(int(c))[:, sel]                  # (M, rows)
        Q = transform.to_fixed(P, times, groups)
        C = np.fft.fft(Q, axis=0) / M
        wf = np.array([fmap.get(int(r), 0.0) for r in rows]) ** 2
        for j in range(nb):
            wf[groups[:, j]] *= coord_w[j]
        energy = (np.abs(C) ** 2) @ wf
        eta = complex(fl.exponents[int(c)])
        k = kk[dominant_harmonic(energy, kk, eta.imag, w0, tie=1e-9)]
        eta_f = eta + 1j * k * w0
        amp = C[k % M]                                          # fixed-frame amplitudes
        ww = np.array([wmap.get(int(r), 0.0) for r in rows]) ** 2
        gw = ww[groups[:, 0]]
        blade = amp[groups]                                     # (G, Nb): coordinate j
        e = {"collective": float(gw @ np.abs(blade[:, 0]) ** 2)}
        fw = np.zeros(len(orders))
        bw = np.zeros(len(orders))
        for j in range(1, nb - (nb % 2 == 0), 2):
            zc, zs = blade[:, j], blade[:, j + 1]
            fw[orders[j]] += gw @ (np.abs(zc + 1j * zs) ** 2 / 4)
            bw[orders[j]] += gw @ (np.abs(zc - 1j * zs) ** 2 / 4)
        if eta_f.imag < 0:                      # report the positive-frequency member
            eta_f = eta_f.conjugate()
            fw, bw = bw, fw
        e["differential"] = float(gw @ np.abs(blade[:, -1]) ** 2) if nb % 2 == 0 else 0.0
        e["forward"], e["backward"] = float(fw.sum()), float(bw.sum())
        total = sum(e.values())
        whirl = max(WHIRLS, key=lambda name: e[name])
        order = {"collective": 0, "differential": nb // 2,
                 "forward": int(np.argmax(fw)), "backward": int(np.argmax(bw))}[whirl]
        shares = {name: (v / total if total > 0 else 0.0) for name, v in e.items()}
        out[int(c)] = FixedFrameMode(exponent=eta_f, whirl=whirl, order=order, shares=shares)
    return out
