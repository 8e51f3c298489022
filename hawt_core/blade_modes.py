"""Modes of one blade clamped to a hub spinning at constant speed (the symmetric modes of the
paper's Table 2).

The blade root sits at radius ``e`` on a hub spinning about ``b3`` at ``Omega0``: in the root
frame the root velocity is ``v = e Omega0 b2`` and the angular velocity ``omega = Omega0 b3``
(plus gravity, if enabled, which then makes the problem periodic: not handled here - the
blade is analysed in its rotating-frame steady state without gravity).
Steps: nonlinear steady state (Newton), exact linearization ``E ydot = A y``
(``E = dR/dydot``, ``A = -dR/dy``), generalized eigen-analysis of the pencil ``(A, E)``,
selection of the physical (finite, in-band) eigenvalues, classification by strain energy.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Optional

import numpy as np
import scipy.linalg as sl
import scipy.sparse as sp
import scipy.sparse.linalg as spl

from .fem.beam import BeamElements
from .fem.sections import mesh_beam
from .jacobian import ColouredJacobian, block_tridiagonal_pattern
from .model import Turbine

FAMILIES = ("axial", "shear", "shear", "torsion", "flap", "lag")


class ConvergenceError(RuntimeError):
    """A Newton iteration did not converge."""


def newton(fun, jac, y0, tol=1e-9, max_iter=30, what="steady state", fixed=None):
    """Newton's method with a sparse LU; ``tol`` is relative to the first residual's scale.

    ``fixed``: indices of unknowns held at their initial values (ignorable coordinates such
    as a free yaw angle, whose columns of the Jacobian vanish, so J is singular): each step
    solves the bordered system ``[[J, B], [P^T, 0]] [dy; mu] = [r; 0]``, ``P`` selecting the
    fixed unknowns and ``B`` fixed pseudo-random columns (generically outside the range of
    J, which makes the bordered matrix regular); for a consistent system ``mu`` vanishes at
    the solution, which is then the one with the fixed unknowns unchanged.
    Raises ConvergenceError naming ``what``, the iteration count and the residual reached.
    """
    y = np.array(y0, dtype=float)
    r = fun(y)
    scale = max(1.0, np.max(np.abs(r)))
    fixed = np.asarray([] if fixed is None else fixed, int)
    n, k = len(y), len(fixed)
    P = sp.csc_matrix((np.ones(k), (fixed, np.arange(k))), shape=(n, k))
    Bcols = np.random.default_rng(12345).standard_normal((n, k))
    for it in range(max_iter):
        if not np.all(np.isfinite(r)):
            raise ConvergenceError(f"{what}: residual became non-finite at iteration {it}")
        if np.max(np.abs(r)) <= tol * scale:
            return y, it
        J = sp.csc_matrix(jac(y))
        if k:
            B = sp.csc_matrix(Bcols * (abs(J).max() / np.sqrt(n)))
            J = sp.bmat([[J, B], [P.T, None]], format="csc")
        try:
            dy = spl.splu(J).solve(np.concatenate([r, np.zeros(k)]))[:n]
        except RuntimeError as exc:  # singular factor
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it} ({exc})") from exc
        y = y - dy
        r = fun(y)
    raise ConvergenceError(f"{what}: Newton did not converge in {max_iter} iterations "
                           f"(max residual {np.max(np.abs(r)):.3e}, tolerance {tol * scale:.3e})")


def equilibrate(A: np.ndarray, E: np.ndarray):
    """Row and column scalings of the pencil (A, E) (eigenvalues are unchanged).

    Returns ``(A_s, E_s, c)`` with ``A_s = R^-1 A C^-1`` (likewise E) and ``c`` the column
    scales: an eigenvector ``z`` of the scaled pencil is ``x = z / c`` of the original one.
    """
    big = np.maximum(np.abs(A), np.abs(E))
    r = big.max(1)
    r[r == 0] = 1.0
    big = big / r[:, None]
    c = big.max(0)
    c[c == 0] = 1.0
    return (A / r[:, None]) / c[None, :], (E / r[:, None]) / c[None, :], c


#: Relative singular-value threshold for the rank decisions of the deflation.
RANK_TOL = 1e-12


class SingularPencilError(RuntimeError):
    """det(A - lambda E) vanishes identically: the linearized model is not well posed."""


_SINGULAR = ("the linearized blade equations are singular (det(A - lambda E) = 0 for all "
             "lambda): check the section data (zero mass or inertia with zero compliance?)")


def deflate_infinite(A: np.ndarray, E: np.ndarray, rank_tol: float = RANK_TOL):
    """Remove the infinite eigenvalues of the regular pencil ``(A, E)``.

    Returns ``(Ar, Er, X)`` with ``Er`` nonsingular, such that the eigenvalues of
    ``Ar z = lam Er z`` are exactly the finite eigenvalues of ``A x = lam E x`` and
    ``x = X z`` their eigenvectors.

    Why: with rigid axial/shear directions the blade is a DAE of index 3.  QZ returns its
    infinite eigenvalues partly as huge finite numbers: a Jordan block of size k at infinity,
    perturbed by round-off, splits into k eigenvalues of size ~ eps^(-1/k), e.g. a +-6e6 per-rev
    real (or imaginary!) pair at N = 32, and no band separates those from the genuine but
    ill-conditioned top of the discrete spectrum in every case.  Deflating is exact instead:
    with ``W`` spanning the left null space of E, every finite eigenvector satisfies
    ``W^T A x = 0``; restricting x to that null space (basis ``N``) and the rows to the
    complement ``P`` of ``W`` gives the smaller pencil ``(P^T A N, P^T E N)`` with the same
    finite eigenpairs and an index lowered by one.  Repeat until E is nonsingular.  The first
    step uses the exact zero rows of E (the algebraic equations); later ones an SVD after
    re-equilibration.
    """
    n = A.shape[0]
    X = np.eye(n)
    first = True
    for _ in range(n + 1):
        A, E, c = equilibrate(A, E)
        X = X / c[None, :]
        m = A.shape[0]
        if m == 0:
            break
        # the constraint rows C = W^T A and the kept rows P^T A, P^T E of this step
        if first:
            first = False
            nonzero = np.any(E != 0, axis=1)
            if nonzero.sum() == m:
                break
            C, PA, PE = A[~nonzero], A[nonzero], E[nonzero]
        else:
            U, s, _ = sl.svd(E)
            r = int((s > s[0] * rank_tol).sum()) if s.size and s[0] > 0 else 0
            if r == m:
                break
            P, W = U[:, :r], U[:, r:]
            C, PA, PE = W.T @ A, P.T @ A, P.T @ E
        _, sc, Vh = sl.svd(C)
        rc = int((sc > sc[0] * rank_tol).sum()) if sc.size and sc[0] > 0 else 0
        if rc < C.shape[0]:
            raise SingularPencilError(_SINGULAR)
        N = Vh[rc:].conj().T
        A, E, X = PA @ N, PE @ N, X @ N
    return A, E, X


def finite_modes(A: np.ndarray, E: np.ndarray, band: float = np.inf):
    """Finite eigenpairs of ``A x = lam E x`` with 0 <= Im(lam) and |lam| < band.

    The infinite eigenvalues are deflated first (:func:`deflate_infinite`); QZ on the reduced
    pencil then keeps ``|beta| > 1e-8 |alpha|`` (after equilibration) and the band (an upper
    bound of the discrete spectrum, see :func:`frequency_bound`) as safety nets.  Returns
    ``(lam, X)`` with X's columns in the unscaled variables.
    """
    Ar, Er, T = deflate_infinite(np.asarray(A, float), np.asarray(E, float))
    if Ar.shape[0] == 0:
        return np.zeros(0, complex), np.zeros((A.shape[0], 0), complex)
    As, Es, c = equilibrate(Ar, Er)
    (alpha, beta), Z = sl.eig(As, Es, homogeneous_eigvals=True)
    ok = np.abs(beta) > 1e-8 * np.abs(alpha)
    lam = np.full(alpha.shape, np.inf, complex)
    lam[ok] = alpha[ok] / beta[ok]
    keep = ok & (np.abs(lam) < band) & (lam.imag >= -1e-9 * np.maximum(1, np.abs(lam)))
    X = T @ (Z[:, keep] / c[:, None])
    return lam[keep], X


def sparse_modes(A, E, count: int, band: float = np.inf, sigma: float = 0.0):
    """The ``count`` finite eigenpairs of ``A x = lam E x`` nearest ``sigma`` with Im >= 0
    (lowest frequencies for sigma = 0), by shift-invert Arnoldi: the largest eigenvalues
    ``mu = 1/(lam - sigma)`` of ``(A - sigma E)^-1 E`` (sparse LU).  Infinite eigenvalues map
    to ``mu = 0`` and never come first."""
    A = sp.csc_matrix(A)
    E = sp.csc_matrix(E)
    n = A.shape[0]
    for s in (sigma, sigma - 1e-3, sigma - 1.0):
        try:
            lu = spl.splu(sp.csc_matrix(A - s * E))
            break
        except RuntimeError:
            continue
    else:
        raise SingularPencilError("A - sigma E is singular for every shift tried")
    op = spl.LinearOperator((n, n), matvec=lambda x: lu.solve(np.asarray(E @ x)),
                            dtype=float)
    k = int(min(2 * count + 6, n - 2))
    mu = None
    for ncv in (3 * k, 5 * k):
        try:
            mu, X = spl.eigs(op, k=k, which="LM", ncv=int(min(n - 1, max(ncv, 40))))
            break
        except spl.ArpackNoConvergence as err:
            if len(err.eigenvalues) >= min(k, 2 * count):
                mu, X = err.eigenvalues, err.eigenvectors
                break
    if mu is None:
        raise ConvergenceError(f"sparse eigen-solver: ARPACK did not converge for the lowest "
                               f"{count} modes; try method='dense'")
    ok = np.abs(mu) > 0
    lam = np.full(mu.shape, np.inf, complex)
    lam[ok] = s + 1.0 / mu[ok]
    keep = ok & (np.abs(lam) < band) & (lam.imag >= -1e-9 * np.maximum(1, np.abs(lam)))
    lam, X = lam[keep], X[:, keep]
    order = np.argsort(np.abs(lam - s), kind="stable")[:count]
    return lam[order], X[:, order]


def frequency_bound(props) -> float:
    """Element-level upper estimate of the discrete spectrum [rad/s].

    Largest over elements of ``sqrt(stiffness / inertia) / h`` for the second-order
    mechanisms (torsion, rotary bending ``sqrt(EI_k / I_k)/h`` - the hourglass-like rotation
    modes of the linear element - axial and shear) and ``sqrt(EI_k / m) / h^2`` for
    translational bending, plus the shear cut-off ``sqrt(GA / I)``.  The genuine discrete
    eigenvalues found so far stay below about 1.2 times this; 100 times it is the band.
    """
    R = props.compliance
    mu = props.mass
    h = props.h
    diagR = np.diagonal(R, axis1=1, axis2=2)           # (N, 6)
    with np.errstate(divide="ignore"):
        stiff = np.where(diagR > 0, 1.0 / np.where(diagR > 0, diagR, 1.0), 0.0)
    m = mu[:, 0, 0]
    inertia = np.diagonal(mu[:, 3:, 3:], axis1=1, axis2=2)  # about the reference line
    cands = []
    tiny = 1e-300
    for k in range(3):                                  # torsion, flap, lag rotations
        cands.append(np.sqrt(stiff[:, 3 + k] / np.maximum(inertia[:, k], tiny)) / h)
        cands.append(np.sqrt(stiff[:, k] / np.maximum(m, tiny)) / h)            # axial/shear
    for k in (1, 2):
        cands.append(np.sqrt(stiff[:, 3 + k] / np.maximum(m, tiny)) / h ** 2)
        cands.append(np.sqrt(stiff[:, k] / np.maximum(inertia[:, 3 - k], tiny)))
    w = np.max(np.stack(cands, 0))
    return float(w) if np.isfinite(w) and w > 0 else np.inf


def _json_number(x):
    x = float(x)
    return x if np.isfinite(x) else None


@dataclass
class Mode:
    """One blade mode. ``frequency_per_rev`` is None (NaN in memory) when not spinning."""

    family: str
    index: int
    frequency_per_rev: float
    frequency_hz: float
    damping_ratio: float
    eigenvalue: complex
    shape: dict = field(repr=False)

    @property
    def frequency_rad_s(self) -> float:
        return float(self.eigenvalue.imag)

    def to_dict(self) -> dict:
        return {"family": self.family, "index": self.index,
                "frequency_per_rev": _json_number(self.frequency_per_rev),
                "frequency_hz": _json_number(self.frequency_hz),
                "damping_ratio": _json_number(self.damping_ratio), "shape": self.shape}


@dataclass
class BladeModesResult:
    rotor_speed: float
    elements: int
    modes: list
    root_force: np.ndarray
    settings: dict

    def to_dict(self) -> dict:
        return {"settings": self.settings, "root_force": [float(f) for f in self.root_force],
                "modes": [m.to_dict() for m in self.modes]}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), allow_nan=False, **kw)

    def frequencies(self, family: Optional[str] = None) -> np.ndarray:
        """Frequencies [rad/s] of the modes (of one family), ascending."""
        return np.array([m.frequency_rad_s for m in self.modes
                         if family is None or m.family == family])

    def table(self) -> str:
        lines = [f"Blade modes, clamped on the hub at {self.rotor_speed:.4g} rad/s, "
                 f"{self.elements} elements ({self.settings.get('method', '')})",
                 f"{'mode':<16}{'per-rev':>12}{'Hz':>12}{'damping':>12}"]
        for m in self.modes:
            pr = (f"{m.frequency_per_rev:>12.5f}" if np.isfinite(m.frequency_per_rev)
                  else f"{'-':>12}")
            lines.append(f"{m.family + ' ' + str(m.index):<16}{pr}"
                         f"{m.frequency_hz:>12.5f}{m.damping_ratio:>12.2e}")
        return "\n".join(lines)

    def plot(self, path, count: int = 6):
        """Mode shapes (flap u3, lead-lag u2, twist theta1 along the span) to a PNG file."""
        from .plotting import plot_blade_modes
        return plot_blade_modes(self, path, count=count)


def check_elements(elements) -> int:
    """Validated element count (an integer >= 1) or ValueError naming the field."""
    if isinstance(elements, bool) or not isinstance(elements, (int, np.integer)):
        try:
            ok = float(elements) == int(elements)
        except (TypeError, ValueError, OverflowError):
            ok = False
        if not ok:
            raise ValueError(f"elements: {elements!r} is not allowed; need an integer >= 1")
    n = int(elements)
    if n < 1:
        raise ValueError(f"elements: {n} is not allowed; need an integer >= 1")
    return n


def check_rotor_speed(speed) -> float:
    """Validated rotor speed (finite, >= 0, rad/s) or ValueError naming the field."""
    try:
        s = float(speed)
    except (TypeError, ValueError):
        raise ValueError(f"rotor_speed: {speed!r} is not allowed; "
                         "need a finite number >= 0 [rad/s]") from None
    if not np.isfinite(s) or s < 0:
        raise ValueError(f"rotor_speed: {speed!r} is not allowed; "
                         "need a finite number >= 0 [rad/s]")
    return s


class SpinningBlade:
    """One blade clamped at radius ``hub_radius`` on a hub spinning at ``rotor_speed``.

    Unknowns and residual rows are those of BeamElements (one beam). The root motion (root
    frame b, constant) is the rigid system's (hawt_core.rigid) for blade 0 with the yaw locked
    and the hub rigid: ``v = e Omega0 b2``, ``omega = Omega0 (sin(beta) b1 + cos(beta) b3)``
    with the precone beta (the coned blade spins about the shaft, not about its own b3, which
    lowers its centrifugal stiffening); undersling and tilt do not change it.
    """

    def __init__(self, turbine: Turbine, elements: Optional[int] = None,
                 rotor_speed: Optional[float] = None):
        from dataclasses import replace
        from .rigid import RigidSystem
        self.turbine = turbine
        self.rotor_speed = check_rotor_speed(turbine.rotor.speed if rotor_speed is None
                                             else rotor_speed)
        n_el = check_elements(turbine.blade.elements if elements is None else elements)
        self.beam = BeamElements(mesh_beam(turbine.blade, n_el))
        self.n = self.beam.n
        clamped = replace(turbine, rotor=replace(turbine.rotor, speed=self.rotor_speed),
                          hub=replace(turbine.hub, teeter=False, counterweight_mass=0.0),
                          nacelle=replace(turbine.nacelle, yaw_free=False), tower=None,
                          gravity=replace(turbine.gravity, enabled=False))
        v, w = RigidSystem(clamped).root_motion(np.zeros(0), np.zeros(0), 0.0)
        self.v, self.w = np.real(v[0]).astype(float), np.real(w[0]).astype(float)
        self._jac = ColouredJacobian(block_tridiagonal_pattern(self.beam.pattern_blocks()))
        self.differential = self.beam.differential

    def residual(self, ydot, y, t=0.0):
        return self.beam.residual(ydot[None], y[None], self.v[None], self.w[None])[0]

    def jacobians(self, ydot, y, t=0.0):
        C = self._jac.n_colours
        rep = lambda a: np.broadcast_to(a, (C,) + np.shape(a))
        V, W = rep(self.v), rep(self.w)
        Jy = self._jac.batched(lambda Y: self.beam.residual(rep(ydot), Y, V, W), y)
        Jd = self._jac.batched(lambda Yd: self.beam.residual(Yd, rep(y), V, W), ydot)
        return Jy, Jd

    def steady_state(self) -> np.ndarray:
        z = np.zeros(self.n)
        y, _ = newton(lambda y: self.residual(z, y), lambda y: self.jacobians(z, y)[0],
                      self.beam.rigid_body_state(self.v, self.w), what="blade steady state")
        return y


def classify_energy(beam: BeamElements, x: np.ndarray) -> np.ndarray:
    """Strain energy of an eigenvector ``x`` (one beam) by direction
    [axial, shear2, shear3, torsion, flap, lag] (compliance-weighted section loads)."""
    _, _, _, _, F, M = beam.nodal(x[None])
    FM = np.concatenate([F[0], M[0]], -1)            # (N, 6) complex
    strain = np.einsum("nij,nj->ni", beam.R, FM)
    return (beam.h[:, None] * np.real(np.conj(FM) * strain)).sum(0)


def mode_shape(beam: BeamElements, x: np.ndarray) -> dict:
    """Real, normalized nodal shape of an eigenvector.

    ``span`` [m]; ``displacement`` u (N+1, 3) and ``rotation`` theta (N+1, 3) in the root
    frame b, scaled so that the largest of |u| and L |theta| is 1 (L the blade length, so that
    units do not decide) and turned to be real there; ``flap`` (u3), ``lag`` (u2) and
    ``twist`` (theta1) repeat the columns used for plotting.
    """
    u, th, _, _, _, _ = beam.nodal(x[None])
    u, th = u[0], th[0]
    L = beam.props.nodes[-1]
    z = np.concatenate([u.ravel(), L * th.ravel()])
    k = np.argmax(np.abs(z))
    phase = z[k] / abs(z[k]) if abs(z[k]) > 0 else 1.0
    scale = abs(z[k]) if abs(z[k]) > 0 else 1.0
    u = np.real(u / phase) / scale
    th = np.real(th / phase) / scale
    return {"span": beam.props.nodes.tolist(), "displacement": u.tolist(),
            "rotation": th.tolist(), "flap": u[:, 2].tolist(), "lag": u[:, 1].tolist(),
            "twist": th[:, 0].tolist()}


#: Above this many unknowns, ``method="auto"`` uses the sparse shift-invert path.
SPARSE_THRESHOLD = 600
#: Default number of modes returned by the sparse path.
DEFAULT_SPARSE_COUNT = 30


def blade_modes(turbine: Turbine, elements: Optional[int] = None,
                rotor_speed: Optional[float] = None, count: Optional[int] = None,
                method: str = "auto", band_factor: float = 100.0) -> BladeModesResult:
    """Modes of one blade clamped on the spinning hub, sorted by frequency.

    ``elements`` (default: the turbine's), ``rotor_speed`` [rad/s] (default: the turbine's).
    ``method``: "dense" (deflation of the infinite eigenvalues + QZ: every finite mode, 3N for
    a rigid-axial, shear-rigid blade), "sparse" (shift-invert Arnoldi about 0 with a sparse LU:
    the lowest ``count`` modes), or "auto" (sparse above SPARSE_THRESHOLD unknowns).
    ``count``: how many of the lowest modes to return (default: all for dense,
    DEFAULT_SPARSE_COUNT for sparse).  ``band_factor``: modes above this many times the
    element-level frequency bound (:func:`frequency_bound`) are discarded as numerical.
    """
    if method not in ("auto", "dense", "sparse"):
        raise ValueError(f"method: {method!r} is not allowed; use 'auto', 'dense' or 'sparse'")
    if count is not None:
        if isinstance(count, bool) or int(count) != count or count < 1:
            raise ValueError(f"count: {count!r} is not allowed; need an integer >= 1")
        count = int(count)
    from .threads import blas_threads
    with blas_threads():
        return _blade_modes(turbine, elements, rotor_speed, count, method, band_factor)


def _blade_modes(turbine, elements, rotor_speed, count, method, band_factor):
    model = SpinningBlade(turbine, elements, rotor_speed)
    y0 = model.steady_state()
    Jy, Jd = model.jacobians(np.zeros(model.n), y0)
    om = model.rotor_speed
    band = band_factor * frequency_bound(model.beam.props)
    if method == "auto":
        method = "sparse" if model.n > SPARSE_THRESHOLD else "dense"
    if method == "sparse":
        k = DEFAULT_SPARSE_COUNT if count is None else count
        lam, X = sparse_modes(-Jy, Jd, k, band=band)
    else:
        lam, X = finite_modes(-Jy.toarray(), Jd.toarray(), band)
    order = np.lexsort((lam.real, np.abs(lam.imag)))
    if count is not None:
        order = order[:count]
    modes = []
    counts = {}
    for j in order:
        x = X[:, j]
        energy = classify_energy(model.beam, x)
        fam = FAMILIES[int(np.argmax(energy))]
        counts[fam] = counts.get(fam, 0) + 1
        w = abs(lam[j])
        modes.append(Mode(family=fam, index=counts[fam],
                          frequency_per_rev=float(lam[j].imag / om) if om > 0 else float("nan"),
                          frequency_hz=float(lam[j].imag / (2 * np.pi)),
                          damping_ratio=float(-lam[j].real / w) if w > 0 else 0.0,
                          eigenvalue=complex(lam[j]), shape=mode_shape(model.beam, x)))
    settings = {"turbine": turbine.name, "elements": model.beam.N, "rotor_speed": om,
                "hub_radius": float(turbine.hub.radius), "method": method,
                "count": count, "unknowns": model.n}
    return BladeModesResult(rotor_speed=om, elements=model.beam.N, modes=modes,
                            root_force=y0[0:3].copy(), settings=settings)
