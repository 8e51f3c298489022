"""Periodic steady state of the turbine by harmonic balance (Fourier collocation).

With gravity, shaft tilt or an asymmetric rotor the steady state is periodic with the rotor
period ``T``. Unknowns: the state at ``M = 2K + 1`` equally spaced times ``t_j = j T / M``
(a trigonometric polynomial of degree K); the time derivative is the exact derivative of that
polynomial, ``ydot_j = sum_k D_jk y_k`` (Fourier differentiation matrix); the residual
``R(ydot_j, y_j, t_j) = 0`` is imposed at every collocation time. Newton's method uses the exact
Jacobian ``blockdiag(dR/dy_j) + blockdiag(dR/dydot_j) (D kron I)``.

Ignorable coordinates (a free yaw angle with no spring: its column of dR/dy is zero) have an
arbitrary mean; it is held at its initial value by a unit diagonal regularization (it changes
the Newton path, not the solution).

Identical, equally spaced blades (an odd number Nb >= 3 of them): the residual has the blade
relabelling symmetry ``R(S ydot, S y, t + T/Nb) = S R(ydot, y, t)`` (assembly/turbine.py
blade_relabelling), so the periodic steady state satisfies ``y(t + T/Nb) = S y(t)`` (if y
solves, so does ``S y(t - T/Nb)``; the steady state is that unique solution). The unknowns
are then the samples in the first 1/Nb of the period only (M divisible by Nb), the others
``y_{j + l M/Nb} = S^l y_j``, and the residual is imposed there: Nb times fewer Jacobians and
unknowns for the same harmonics (the symmetry is checked on the residual first; see
_relabelling_symmetry).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional

import warnings

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from ..numerics.newton import ConvergenceError, newton
from .equilibrium import check_equilibrium_exists
from .steady import constant_steady_state, ignorable_columns
from .trim import generator_trim


def fourier_differentiation(M: int, period: float) -> np.ndarray:
    """Real matrix D (M, M) with ``D @ f(t_j) = f'(t_j)`` for trigonometric polynomials of
    degree (M-1)/2 sampled at ``t_j = j period / M`` (M odd)."""
    if M % 2 == 0:
        raise ValueError(f"harmonic balance: M = {M} samples must be odd")
    k = np.fft.fftfreq(M, d=1.0 / M)
    w = 2 * np.pi / period
    F = np.fft.fft(np.eye(M), axis=0)
    return np.real(np.fft.ifft(1j * k[:, None] * w * F, axis=0))


@dataclass
class PeriodicSteadyState:
    """Samples ``states[j]`` at ``times[j]`` over one period; ``at(t)`` interpolates."""

    times: np.ndarray
    states: np.ndarray
    period: float
    iterations: int
    constant: bool = False
    harmonics: int = 0
    interpolation_error: float = 0.0

    def _fourier(self):
        """(c, k): Fourier coefficients of ``states`` and their harmonics, computed on first
        use (again if ``states`` is replaced; do not modify it in place)."""
        cached = self.__dict__.get("_fourier_cache")
        if cached is None or cached[0] is not self.states:
            M = len(self.times)
            cached = (self.states, np.fft.fft(self.states, axis=0) / M,
                      np.fft.fftfreq(M, d=1.0 / M))
            self.__dict__["_fourier_cache"] = cached
        return cached[1], cached[2]

    def at(self, t: float) -> np.ndarray:
        """State y(t) (n,) [SI units of the state layout] by the Fourier series of the
        samples; ``t`` [s], any value (periodic)."""
        if self.constant:
            return self.states[0].copy()
        c, k = self._fourier()
        ph = np.exp(2j * np.pi * k * (t % self.period) / self.period)
        return np.real(ph @ c)

    def rate_at(self, t: float) -> np.ndarray:
        """Rate dy/dt (n,) [state units / s] at ``t`` [s] (derivative of the series)."""
        if self.constant:
            return np.zeros(self.states.shape[1])
        c, k = self._fourier()
        w = 2 * np.pi / self.period
        ph = 1j * k * w * np.exp(2j * np.pi * k * (t % self.period) / self.period)
        return np.real(ph @ c)


#: Residual between the collocation times, relative to the load scale, that ends the doubling
#: of harmonics, unless the model declares its own ``interpolation_tol`` (TurbineModel does in
#: wind: assembly/turbine.py AERO_INTERPOLATION_TOL).
INTERPOLATION_TOL = 1e-8


def periodic_steady_state(model, harmonics: int = 8, tol: float = 1e-9, max_iter: int = 25,
                          progress=None, interpolation_tol: Optional[float] = None,
                          max_harmonics: int = 48) -> PeriodicSteadyState:
    """Steady state of ``model`` (a TurbineModel): the constant one when it exists (no
    gravity, tilt or asymmetry), otherwise the periodic one by harmonic balance, starting with
    ``harmonics`` harmonics and doubling them (up to ``max_harmonics``; 1.5 times with the
    blade-relabelling symmetry, see the module docstring) until the residual
    between the collocation times is below ``interpolation_tol`` relative to the load scale
    (default the model's ``interpolation_tol``, else INTERPOLATION_TOL).
    Raises ConvergenceError when Newton does not converge, and NoEquilibrium (a ValueError,
    in a fraction of a second) when no steady state can exist (solvers/equilibrium.py)."""
    if interpolation_tol is None:
        interpolation_tol = getattr(model, "interpolation_tol", INTERPOLATION_TOL)
    if model.rotor_speed <= 0:
        raise ValueError(f"rotor_speed: {model.rotor_speed} is not allowed for a periodic "
                         "steady state; need > 0 [rad/s]")
    generator_trim(model)            # a free generator in wind: its torque is trimmed
    check_equilibrium_exists(model)
    if not _gravity_turns(model):
        try:
            y = constant_steady_state(model, check=False)
            return PeriodicSteadyState(times=np.array([0.0]), states=y[None],
                                       period=model.period, iterations=0, constant=True)
        except (ValueError, ConvergenceError):
            pass  # genuinely periodic (or no constant state found): harmonic balance
    T = model.period
    scale = model.load_scale()
    guess = None
    symmetry = _relabelling_symmetry(model)
    H = int(harmonics) if symmetry is None else _symmetric_harmonics(int(harmonics),
                                                                      symmetry[1])
    try:
        guess = _harmonic_balance(model, H, tol, max_iter, progress, None, symmetry)
    except ConvergenceError as exc:
        guess = _continuation(model, H, tol, max_iter, progress, exc, symmetry)
    while True:
        ps = guess if guess.harmonics == H else _harmonic_balance(model, H, tol, max_iter,
                                                                  progress, guess, symmetry)
        mids = (np.arange(2 * H + 1) + 0.5) * T / (2 * H + 1)
        err = max(np.abs(model.residual(ps.rate_at(t), ps.at(t), t)).max() for t in mids[::3])
        ps.interpolation_error = float(err / scale)
        # with the symmetry the next truncation is 1.5 H rounded up to one whose sample count
        # Nb divides (unknowns and Jacobians grow with (2H + 1) / Nb only)
        H_next = (2 * H if symmetry is None
                  else _symmetric_harmonics(int(math.ceil(1.5 * H)), symmetry[1]))
        if ps.interpolation_error <= interpolation_tol or H_next > max_harmonics:
            if ps.interpolation_error > interpolation_tol:
                warnings.warn(f"periodic steady state: residual between collocation times "
                              f"{ps.interpolation_error:.1e} (relative) with {H} harmonics",
                              RuntimeWarning, stacklevel=2)
            return ps
        guess, H = ps, H_next


def _gravity_turns(model) -> bool:
    """True when gravity turns in the spinning blades' frames (gravity on, a turning rotor,
    a shaft that is not vertical): the steady state is periodic and a constant one need not
    be tried (that attempt, Newton on the time-invariant equations and then rejected, cost
    0.6 s of the NREL 5-MW's 7 s Floquet analysis at 32 elements).  Other periodic causes
    (shear, yaw, an unbalanced rotor) still try the constant state first: R(0, y0, t) of the
    initial guess does not tell (the mixed beam's force unknowns are zero there, so a
    balanced one-bladed rotor's blade pulls nothing against its counterweight)."""
    rigid = getattr(model, "rigid", None)
    return (bool(getattr(model, "gravity", False)) and np.isfinite(model.period)
            and rigid is not None and abs(np.cos(getattr(rigid, "tilt", 0.0))) > 1e-9)


#: Largest relative difference between ``R(S ydot, S y, t + T/Nb)`` and ``S R(ydot, y, t)``
#: (relative to the load scale) at which the harmonic balance uses the blade-relabelling
#: symmetry; round-off is ~1e-15 of it, a blade that differs from the others far more.
SYMMETRY_CHECK_TOL = 1e-10


def _relabelling_symmetry(model):
    """(S, Nb) when the harmonic balance may use the blade-relabelling symmetry: an odd
    number Nb >= 3 of blades (an odd sample count M = 2H + 1 must be divisible by Nb), the
    model declaring S, and the residual obeying ``R(S ydot, S y, t + T/Nb) = S R(ydot, y,
    t)`` at a perturbed state and rate (a fixed pseudo-random perturbation of the initial
    guess, so that stiffness, mass and aerodynamic terms all take part) to
    SYMMETRY_CHECK_TOL of the load scale; else None (the whole period is collocated)."""
    Nb = int(getattr(model, "n_blades", 1))
    if Nb < 3 or Nb % 2 == 0 or not hasattr(model, "blade_relabelling"):
        return None
    try:
        S = sp.csr_matrix(model.blade_relabelling())
    except ValueError:
        return None
    rng = np.random.default_rng(20261204)
    y = model.initial_guess() + 1e-6 * rng.standard_normal(model.n)
    yd = 1e-6 * rng.standard_normal(model.n)
    t = 0.3 * model.period
    lhs = model.residual(S @ yd, S @ y, t + model.period / Nb)
    rhs = S @ model.residual(yd, y, t)
    if not np.all(np.isfinite(lhs)) or \
            np.abs(lhs - rhs).max() > SYMMETRY_CHECK_TOL * model.load_scale():
        return None
    return S, Nb


def _symmetric_harmonics(H: int, Nb: int) -> int:
    """The smallest truncation >= H whose sample count 2H + 1 is divisible by Nb (odd)."""
    while (2 * H + 1) % Nb:
        H += 1
    return H


#: Continuation: the first homotopy parameter, and the smallest step factor before giving up.
CONTINUATION_START = 1e-4
CONTINUATION_MIN_STEP = 1.02


def homotopy_turbine(turbine, lam: float):
    """The turbine with its periodic forcing scaled down by ``lam`` in (0, 1]: gravity times
    lam and, with a free yaw bearing, the nacelle's yaw inertia divided by lam (the yaw
    response to an imbalance scales as 1/inertia, and a free yaw angle has no resonance to
    cross on the way).  lam = 1 is the turbine itself."""
    from dataclasses import replace
    out = turbine
    if turbine.gravity.enabled:
        out = replace(out, gravity=replace(out.gravity, g=out.gravity.g * lam))
    if turbine.nacelle.yaw_free:
        out = replace(out, nacelle=replace(out.nacelle,
                                           yaw_inertia=out.nacelle.yaw_inertia / lam))
    return out


def _homotopy_description(turbine) -> str:
    """What homotopy_turbine scales, for this turbine."""
    parts = (["gravity x lam"] if turbine.gravity.enabled else []) + \
        (["free-yaw inertia / lam"] if turbine.nacelle.yaw_free else [])
    return ", ".join(parts)


def _continuation_hint(turbine) -> str:
    """Advice fitting the turbine's own degrees of freedom (none for what it lacks)."""
    if turbine.nacelle.yaw_free and not turbine.nacelle.yaw_stiffness:
        return (" (an unbalanced rotor on a free yaw bearing without a spring may have none; "
                "yaw damping, a yaw spring or hub.counterweight_mass help)")
    if turbine.nacelle.yaw_free:
        return (" (a soft yaw spring under an unbalanced rotor may have none; a stiffer "
                "nacelle.yaw_stiffness or a balanced rotor helps)")
    return " (try more harmonics, a finer mesh, or a rotor speed away from a resonance)"


def _continuation(model, harmonics, tol, max_iter, progress, first_error, symmetry=None):
    """Harmonic balance by natural-parameter continuation from a weakly forced turbine
    (homotopy_turbine at CONTINUATION_START) to the turbine itself, each solution the next
    one's starting guess; the step (a factor on lam) grows after a success and shrinks after
    a failure.  Raises ConvergenceError saying where the continuation stalled."""
    T0 = model.turbine
    if not (T0.gravity.enabled or T0.nacelle.yaw_free):
        raise first_error
    lam, step, guess, last = CONTINUATION_START, 10.0, None, None
    while True:
        m = model.with_turbine(homotopy_turbine(T0, lam)) if lam < 1 else model
        if progress is not None:
            progress(0.5, f"periodic steady state: continuation at {lam:.3g}")
        try:
            ps = _harmonic_balance(m, harmonics, tol, max_iter, None, guess, symmetry)
        except ConvergenceError:
            if last is None or step < CONTINUATION_MIN_STEP:
                where = "its start" if last is None else f"{last:.4g}"
                raise ConvergenceError(
                    f"periodic steady state: Newton did not converge from the rotor in rigid "
                    f"rotation ({first_error}), and a continuation from a weakly forced "
                    f"turbine ({_homotopy_description(T0)}, lam from {CONTINUATION_START:g} "
                    f"to 1) stalled at lam = {where}: no periodic steady state near that "
                    f"family{_continuation_hint(T0)}") from None
            step = float(np.sqrt(step))
            lam = min(1.0, last * step)
            continue
        if lam >= 1.0:
            return ps
        guess, last = ps, lam
        step = min(10.0, step * step)
        lam = min(1.0, lam * step)


#: Harmonic-balance systems of 3+ blades with more unknowns than this solve each Newton step
#: by GMRES, preconditioned with the time-averaged Jacobian in multi-blade coordinates (where
#: an isotropic rotor's coefficients are nearly constant): one sparse LU of size n per
#: harmonic instead of one of the whole (2H + 1) n system, whose fill-in is that of a dense
#: coupling in time (NREL 5-MW, 8 harmonics: 8 s per LU, 50 million non-zeros).  Even at
#: 9500 unknowns (4 elements, 8 harmonics) GMRES wins: the steady state at 15 m/s takes 5.8
#: instead of 9.2 s, the exponents about it agree to 8e-10.
ITERATIVE_UNKNOWNS = 3000


class _AveragedPreconditioner:
    """Inverse of ``I x Jy_bar + D x Jd_bar`` (the harmonic-balance Jacobian with time-averaged
    blocks), applied harmonic by harmonic: ``(Jy_bar + i k w Jd_bar) q_k = r_k``.  The
    averages are taken in multi-blade coordinates ``y = T(t) z`` (rows by ``T(t)^-1``), where
    an isotropic rotor's coefficients vary only with gravity (3+ blades)."""

    def __init__(self, model, jy, jd, times, period):
        from .multiblade import MultiBladeTransform
        self.M, self.n = len(times), model.n
        tr = MultiBladeTransform(model)
        self.T = [tr.matrix(t) for t in times]
        self.Ti = [tr.inverse(t) for t in times]
        rates = [tr.rate(t) for t in times]
        jy_bar = sum(Ti @ (a @ T + b @ R) for Ti, T, R, a, b
                     in zip(self.Ti, self.T, rates, jy, jd)) / self.M
        jd_bar = sum(Ti @ b @ T for Ti, T, b in zip(self.Ti, self.T, jd)) / self.M
        w = 2 * np.pi / period
        H = (self.M - 1) // 2
        self.lu = [spl.splu(sp.csc_matrix(jy_bar + 1j * k * w * jd_bar)) for k in range(H + 1)]

    def solve(self, r):
        R = np.asarray(r).reshape(self.M, self.n)
        Rz = np.stack([Ti @ R[j] for j, Ti in enumerate(self.Ti)])
        C = np.fft.rfft(Rz, axis=0)
        Q = np.stack([lu.solve(C[k]) for k, lu in enumerate(self.lu)])
        q = np.fft.irfft(Q, n=self.M, axis=0)
        return np.concatenate([T @ q[j] for j, T in enumerate(self.T)])


def _symmetric_differentiation(D: np.ndarray, S, Nb: int) -> sp.csr_matrix:
    """The Fourier differentiation of the reduced samples: ``ydot_j = sum_l sum_i
    D[j, i + l m] S^l y_i`` for j, i < m = M / Nb (the sample at ``t_i + l T / Nb`` is
    ``S^l y_i``), as one sparse (m n, m n) matrix."""
    M = D.shape[0]
    m = M // Nb
    n = S.shape[0]
    Sl = sp.identity(n, format="csr")
    out = None
    for l in range(Nb):
        part = sp.kron(sp.csr_matrix(D[:m, l * m:(l + 1) * m]), Sl, format="csr")
        out = part if out is None else out + part
        Sl = (S @ Sl).tocsr()
    return out


def _expand(Yr: np.ndarray, S, Nb: int) -> np.ndarray:
    """The samples over the whole period (M, n) from those over its first 1/Nb (m, n):
    block l is ``S^l`` applied to the reduced samples."""
    blocks, Z = [Yr], Yr
    for _ in range(1, Nb):
        Z = (S @ Z.T).T
        blocks.append(Z)
    return np.concatenate(blocks)


def _harmonic_balance(model, harmonics, tol, max_iter, progress, guess,
                      symmetry=None) -> PeriodicSteadyState:
    M = 2 * harmonics + 1
    T = model.period
    times = np.arange(M) * T / M
    D = fourier_differentiation(M, T)
    n = model.n
    if symmetry is not None:
        # the unknowns are the samples over the first 1/Nb of the period (module docstring)
        S, Nb = symmetry
        if M % Nb:
            raise ValueError(f"harmonic balance: {M} samples are not divisible by {Nb} blades")
        m = M // Nb
        KD = _symmetric_differentiation(D, S, Nb)
    else:
        m = M
        KD = sp.kron(sp.csr_matrix(D), sp.identity(n), format="csr")
    t_col = times[:m]                 # collocation times
    Y = np.tile(model.initial_guess(), (m, 1)) if guess is None \
        else np.array([guess.at(t) for t in t_col])

    def rates(Y):
        return (KD @ Y.ravel()).reshape(m, n)

    def residual(Yflat):
        Y = Yflat.reshape(m, n)
        Yd = rates(Y)
        r = np.concatenate([model.residual(Yd[j], Y[j], t_col[j]) for j in range(m)])
        if progress is not None:
            progress(0.5, f"harmonic balance ({harmonics} harmonics): residual {np.abs(r).max():.2e}")
        return r

    blocks = {}
    # the first collocation time's linearization at the start: Newton's first Jacobian
    # reuses it, and from a start at rest it also finds the ignorable coordinates below
    start, Yd0 = Y.ravel().copy(), rates(Y)
    first = model.jacobians(Yd0[0], Y[0], t_col[0])

    def jacobian(Yflat):
        Y = Yflat.reshape(m, n)
        Yd = rates(Y)
        reuse = np.array_equal(Yflat, start)
        jy, jd = zip(*(first if reuse and j == 0 else model.jacobians(Yd[j], Y[j], t_col[j])
                       for j in range(m)))
        blocks["jy"], blocks["jd"] = jy, jd
        return (sp.block_diag(jy, format="csr") + sp.block_diag(jd, format="csr") @ KD).tocsc()

    def krylov(J, r):
        """GMRES on J dy = r with the averaged preconditioner; None (-> sparse LU) if it
        does not reach its tolerance."""
        if m * n <= ITERATIVE_UNKNOWNS or model.n_blades < 3:
            return None      # small, or one or two blades: strongly periodic, the LU wins
        if blocks.get("preconditioned") is not J:     # Newton keeps J while it contracts
            # with the symmetry, multi-blade coordinates are periodic with T / Nb: the
            # preconditioner works on the reduced samples as a period of its own
            blocks["pre"] = _AveragedPreconditioner(model, blocks["jy"], blocks["jd"], t_col,
                                                    T * m / M)
            blocks["preconditioned"] = J
        pre = blocks["pre"]
        P = spl.LinearOperator(J.shape, matvec=pre.solve, dtype=float)
        dy, info = spl.gmres(J, r, M=P, rtol=1e-10, atol=0.0, restart=60, maxiter=10)
        return dy if info == 0 and np.all(np.isfinite(dy)) else None

    # ignorable coordinates (a free yaw angle) are defined up to a constant: hold them at
    # their value at t = 0 (bordered Newton steps, see blade_modes.newton)
    ign = ignorable_columns(first[0] if not np.any(Yd0[0])
                            else model.jacobians(np.zeros(n), Y[0], times[0])[0])
    # a free generator's torque, trimmed (solvers/trim.py): its azimuth is held at the
    # first sample, the torque solved for
    trim = generator_trim(model)
    border = None
    if trim is not None:
        ign, border = trim.border(ign, residual, Y.ravel())
    Yflat, it = newton(residual, jacobian, Y.ravel(), tol=tol, max_iter=max_iter,
                       what=f"periodic steady state (harmonic balance, {harmonics} harmonics)",
                       fixed=ign, linear_solve=krylov, border=border,
                       # the tolerance's scale at least the loads the state balances (a warm
                       # start's small first residual would ask for less than the round-off
                       # of the blade-root rows)
                       min_scale=model.load_scale(),
                       # the chord method where each Jacobian is dear (GMRES-sized systems);
                       # small ones keep Newton's quadratic last step (a steady state far
                       # below the tolerance, whose symmetry Fast Floquet relies on)
                       reuse_jacobian=m * n > ITERATIVE_UNKNOWNS and model.n_blades >= 3)
    states = Yflat.reshape(m, n)
    if symmetry is not None:
        states = _expand(states, *symmetry)
    return PeriodicSteadyState(times=times, states=states, period=T, iterations=it,
                               harmonics=harmonics)
