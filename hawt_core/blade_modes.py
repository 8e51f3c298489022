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


def newton(fun, jac, y0, tol=1e-9, max_iter=30, what="steady state"):
    """Newton's method with a sparse LU; ``tol`` is relative to the first residual's scale.

    Raises ConvergenceError naming ``what``, the iteration count and the residual reached.
    """
    y = np.array(y0, dtype=float)
    r = fun(y)
    scale = max(1.0, np.max(np.abs(r)))
    for it in range(max_iter):
        if not np.all(np.isfinite(r)):
            raise ConvergenceError(f"{what}: residual became non-finite at iteration {it}")
        if np.max(np.abs(r)) <= tol * scale:
            return y, it
        J = jac(y)
        try:
            dy = spl.splu(sp.csc_matrix(J)).solve(r)
        except RuntimeError as exc:  # singular factor
            raise ConvergenceError(f"{what}: singular Jacobian at iteration {it} ({exc})") from exc
        y = y - dy
        r = fun(y)
    raise ConvergenceError(f"{what}: Newton did not converge in {max_iter} iterations "
                           f"(max residual {np.max(np.abs(r)):.3e}, tolerance {tol * scale:.3e})")


def equilibrate(A: np.ndarray, E: np.ndarray):
    """Row and column scalings of the pencil (A, E) (eigenvalues are unchanged)."""
    big = np.maximum(np.abs(A), np.abs(E))
    r = big.max(1)
    r[r == 0] = 1.0
    big = big / r[:, None]
    c = big.max(0)
    c[c == 0] = 1.0
    return (A / r[:, None]) / c[None, :], (E / r[:, None]) / c[None, :], c


def finite_modes(A: np.ndarray, E: np.ndarray, band: float):
    """Finite eigenpairs of ``A x = lam E x`` with 0 <= Im(lam) and |lam| < band.

    Infinite eigenvalues (the algebraic part of the DAE) come out of QZ with a tiny beta, or as
    huge finite numbers: the band removes both.  Returns (lam, X) with X's columns in the
    unscaled variables.
    """
    As, Es, c = equilibrate(A, E)
    (alpha, beta), X = sl.eig(As, Es, homogeneous_eigvals=True)
    ok = np.abs(beta) > 1e-8 * np.abs(alpha)
    lam = np.full(alpha.shape, np.inf, complex)
    lam[ok] = alpha[ok] / beta[ok]
    keep = ok & (np.abs(lam) < band) & (lam.imag >= -1e-9 * np.maximum(1, np.abs(lam)))
    X = X[:, keep] / c[:, None] if X.ndim == 2 else X
    return lam[keep], X


@dataclass
class Mode:
    family: str
    index: int
    frequency_per_rev: float
    frequency_hz: float
    damping_ratio: float
    eigenvalue: complex
    shape: dict = field(repr=False)

    def to_dict(self) -> dict:
        return {"family": self.family, "index": self.index,
                "frequency_per_rev": self.frequency_per_rev, "frequency_hz": self.frequency_hz,
                "damping_ratio": self.damping_ratio, "shape": self.shape}


@dataclass
class BladeModesResult:
    rotor_speed: float
    elements: int
    modes: list
    root_force: np.ndarray
    settings: dict

    def to_dict(self) -> dict:
        return {"settings": self.settings, "modes": [m.to_dict() for m in self.modes]}

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), **kw)

    def table(self) -> str:
        lines = [f"Blade modes, clamped on the hub at {self.rotor_speed:.4g} rad/s, "
                 f"{self.elements} elements",
                 f"{'mode':<16}{'per-rev':>12}{'Hz':>12}{'damping':>12}"]
        for m in self.modes:
            lines.append(f"{m.family + ' ' + str(m.index):<16}{m.frequency_per_rev:>12.5f}"
                         f"{m.frequency_hz:>12.5f}{m.damping_ratio:>12.2e}")
        return "\n".join(lines)

    def plot(self, path, count: int = 6):
        """Mode shapes (flap u3, lead-lag u2, twist theta1 along the span) to a PNG file."""
        from .plotting import plot_blade_modes
        return plot_blade_modes(self, path, count=count)


class SpinningBlade:
    """One blade clamped at radius ``hub_radius`` on a hub spinning at ``rotor_speed``.

    Unknowns and residual rows are those of BeamElements (one beam). The root motion is
    ``v = e Omega0 b2``, ``omega = Omega0 b3`` (root frame), constant.
    """

    def __init__(self, turbine: Turbine, elements: Optional[int] = None,
                 rotor_speed: Optional[float] = None):
        self.turbine = turbine
        self.rotor_speed = float(turbine.rotor.speed if rotor_speed is None else rotor_speed)
        if not np.isfinite(self.rotor_speed) or self.rotor_speed < 0:
            raise ValueError(f"rotor_speed: {self.rotor_speed!r} is not allowed; "
                             "need a finite number >= 0 [rad/s]")
        self.beam = BeamElements(mesh_beam(turbine.blade, elements))
        self.n = self.beam.n
        e = turbine.hub.radius
        self.v = np.array([0.0, e * self.rotor_speed, 0.0])
        self.w = np.array([0.0, 0.0, self.rotor_speed])
        self._jac = ColouredJacobian(block_tridiagonal_pattern(self.beam.pattern_blocks()))
        self.differential = self.beam.differential

    def residual(self, ydot, y, t=0.0):
        return self.beam.residual(ydot[None], y[None], self.v[None], self.w[None])[0]

    def jacobians(self, ydot, y, t=0.0):
        Jy = self._jac(lambda yy: self.residual(ydot, yy), y)
        Jd = self._jac(lambda yd: self.residual(yd, y), ydot)
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
    """Real, normalized nodal shape of an eigenvector: span [m], u [m], theta [-]."""
    u, th, _, _, _, _ = beam.nodal(x[None])
    u, th = u[0], th[0]
    L = beam.props.nodes[-1]
    # displacements and rotations weighted so that units do not decide: rotation * length
    z = np.concatenate([u.ravel(), L * th.ravel()])
    k = np.argmax(np.abs(z))
    phase = z[k] / abs(z[k]) if abs(z[k]) > 0 else 1.0
    scale = abs(z[k]) if abs(z[k]) > 0 else 1.0
    u = np.real(u / phase) / scale
    th = np.real(th / phase) / scale
    return {"span": beam.props.nodes.tolist(), "displacement": u.tolist(),
            "rotation": th.tolist()}


def blade_modes(turbine: Turbine, elements: Optional[int] = None,
                rotor_speed: Optional[float] = None, band_per_rev: float = 1e4) -> BladeModesResult:
    """Modes of one blade clamped on the spinning hub, sorted by frequency.

    ``band_per_rev``: eigenvalues beyond this many per-rev (or rad/s when not spinning) are
    treated as belonging to the algebraic (infinite) part of the pencil.
    """
    model = SpinningBlade(turbine, elements, rotor_speed)
    y0 = model.steady_state()
    Jy, Jd = model.jacobians(np.zeros(model.n), y0)
    A, E = -Jy.toarray(), Jd.toarray()
    om = model.rotor_speed
    ref = om if om > 0 else 1.0
    lam, X = finite_modes(A, E, band_per_rev * ref)
    modes = []
    counts = {}
    order = np.argsort(np.abs(lam.imag))
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
    settings = {"rotor_speed": om, "elements": model.beam.N, "turbine": turbine.name}
    return BladeModesResult(rotor_speed=om, elements=model.beam.N, modes=modes,
                            root_force=y0[0:3].copy(), settings=settings)
