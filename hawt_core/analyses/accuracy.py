"""Discretization error of reported frequencies, and a mesh chosen for an accuracy.

hawt's mixed beam elements are second order: a frequency computed with N elements per blade
is ``f_N = f + c / N^2 + O(N^-4)``.  Two meshes N1 < N2 give the Richardson estimate of the
error of the finer one,

    err(f_N2) ~ (f_N2 - f_N1) / ((N2 / N1)^2 - 1),     relative: err / f_N2,

and the extrapolated value ``f_N2 + err``.  The blade tests check the estimate against an
independent Euler-Bernoulli solution (tests/test_accuracy.py): for the NREL 5-MW and IEA
15-MW blades at N = 16/32 it is within a factor 1.5 of the true error for the four lowest
bending modes, and conservative (1.8 and 4.9 times the true error) for the fifth, whose
coarse mesh is outside the asymptotic range.

``with_error_estimates(run, n)`` runs an analysis at N and N/2 (coarse, about a quarter of
the cost for sparse models) and attaches ``frequency_error`` (relative, signed: converged
minus reported, over reported) to every mode it can match by label (family, symmetry,
index); ``converge(run, n0, tol)`` raises N (by the second-order law, 1.25x to 2.5x a step)
until every matched mode's estimated error is below ``tol``.  A flexible tower is refined with
the blades (its elements scaled by the same factor).  The modes the tolerance applies to
are the caller's (``in_scope``: the command line's --count / --max-hz, by default the modes
it prints): a mesh's highest modes are never converged, and a torsion mode at 60 Hz must not
hold the flap modes' mesh hostage; the mode that limits the mesh is named.

The p-version (blade order p >= 2, fem/spectral.py) is estimated from order p - 1 on the same
mesh, not from half the elements: on the shipped blades halving a p-mesh leaves the
asymptotic range (Richardson's estimate over the true error: -333 to 574 at order 4, 4
elements), while the difference to order p - 1 is above the true error's maximum over the six
lowest modes at every mesh measured (1.0 to 60 times it; per mode 0.1 to 4000: a bound on
the largest, not on each).
"""
from __future__ import annotations

import math
from typing import Callable, Optional

__all__ = ["richardson", "with_error_estimates", "converge", "check_accuracy", "mode_name",
           "MAX_ELEMENTS_CHOSEN", "ACCURACY_RANGE"]

#: Largest mesh ``converge`` goes to (elements per blade).
MAX_ELEMENTS_CHOSEN = 256

#: Accepted relative accuracies: from ACCURACY_RANGE[0] up to (not including) [1].
ACCURACY_RANGE = (1e-6, 0.5)


def check_accuracy(tol) -> float:
    """A requested relative accuracy, or ValueError naming it and the allowed range (the one
    check the API and the command line share)."""
    lo, hi = ACCURACY_RANGE
    ok = isinstance(tol, (int, float)) and not isinstance(tol, bool) and lo <= tol < hi
    if not ok:
        raise ValueError(f"accuracy: {tol!r} is not allowed; need a relative error from "
                         f"{lo:g} to {hi:g}, e.g. 1e-3")
    return float(tol)


def richardson(f_coarse: float, f_fine: float, n_coarse: int, n_fine: int) -> float:
    """Estimated relative error of ``f_fine`` (second order): (converged - f_fine) / f_fine."""
    r = (n_fine / n_coarse) ** 2
    return (f_fine - f_coarse) / (r - 1.0) / f_fine if f_fine else 0.0


def _key(m):
    return (m.family, getattr(m, "symmetry", None), m.index)


def mode_name(m) -> str:
    """A mode's name for messages: "torsion 12 (59.15 Hz)"."""
    sym = getattr(m, "symmetry", None)
    words = " ".join(str(w) for w in (m.family, sym, m.index) if w not in (None, ""))
    return f"{words} ({m.frequency_hz:.4g} Hz)"


def attach_errors(coarse, fine, n_coarse: int, n_fine: int,
                  in_scope: Optional[Callable[[object], bool]] = None,
                  orders: Optional[tuple] = None) -> float:
    """Set ``frequency_error`` on ``fine``'s modes from ``coarse`` (matched by label; zero
    frequencies and unmatched modes get None); returns the largest |error| (0 if none) of
    the modes ``in_scope(mode)`` selects (default: every mode), and records that mode's
    name in ``settings["error_estimate"]["limiting_mode"]``.  ``orders`` (p - 1, p): the
    p-version's estimate, the difference to order p - 1 on the same mesh (n_coarse ==
    n_fine); None: Richardson from n_coarse to n_fine elements (second order)."""
    by_key = {_key(m): m for m in coarse.modes}
    worst, limiting = 0.0, None
    for m in fine.modes:
        c = by_key.get(_key(m))
        if c is None or not m.frequency_hz > 1e-9 or not c.frequency_hz > 1e-9:
            m.frequency_error = None
            continue
        e = (richardson(c.frequency_hz, m.frequency_hz, n_coarse, n_fine) if orders is None
             else (m.frequency_hz - c.frequency_hz) / m.frequency_hz)
        m.frequency_error = float(e)
        if (in_scope is None or in_scope(m)) and abs(e) >= worst:
            worst, limiting = abs(e), m
    fine.settings["error_estimate"] = {"method": "Richardson (second order)" if orders is None
                                       else "difference to order p - 1 (an upper bound)",
                                       "elements": [int(n_coarse), int(n_fine)],
                                       "orders": None if orders is None else list(orders),
                                       "largest_relative_error": worst,
                                       "limiting_mode": None if limiting is None
                                       else mode_name(limiting)}
    return worst


def with_error_estimates(run: Callable[..., object], n: int, order: int = 1):
    """The fine result ``run(n)`` with estimates: for the paper's element (``order`` 1) from
    ``run(max(1, n // 2))`` (Richardson); for the p-version from ``run(n, order - 1)`` (the
    same mesh one degree lower: its error bounds the finer one's, which falls like
    1/N^(2p); halving a p-mesh leaves the asymptotic range, and Richardson's estimate then
    has the wrong size and even sign, bench measurements in the module docstring)."""
    n, order = int(n), int(order)
    fine = run(n)
    if order > 1:
        attach_errors(run(n, order - 1), fine, n, n, orders=(order - 1, order))
        return fine
    coarse_n = max(1, n // 2)
    if coarse_n == n:
        return fine
    attach_errors(run(coarse_n), fine, coarse_n, n)
    return fine


def converge(run: Callable[..., object], n0: int, tol: float,
             progress: Optional[Callable[[str], None]] = None,
             in_scope: Optional[Callable[[object], bool]] = None, scope: str = "every mode",
             order: int = 1):
    """The result of ``run(N)`` with N raised from ``n0`` until the estimated relative error
    of every matched mode ``in_scope(mode)`` selects (default: every mode of the result;
    ``scope`` says which in messages, e.g. "the 10 lowest modes") is <= ``tol``.
    ValueError if that would exceed MAX_ELEMENTS_CHOSEN (naming the mode that limits it),
    and for a ``tol`` outside ACCURACY_RANGE."""
    tol = check_accuracy(tol)
    order = int(order)
    if order > 1:
        return _converge_p(run, int(n0), tol, progress, in_scope, scope, order)
    n_prev = max(1, int(n0) // 2)
    prev = run(n_prev)
    n = max(n_prev + 1, int(n0))
    while True:
        res = run(n)
        worst = attach_errors(prev, res, n_prev, n, in_scope)
        limiting = res.settings["error_estimate"]["limiting_mode"]
        if progress is not None:
            progress(f"{n} elements: largest estimated error {worst:.2e}"
                     + (f" ({limiting})" if limiting else ""))
        if worst <= tol:
            res.settings["accuracy"] = tol
            return res
        # second-order law, capped: an estimate from a coarse pair is conservative (its
        # coarse mesh is outside the asymptotic range), so the next pair refines it
        grow = min(2.5, max(1.25, math.sqrt(worst / tol) * 1.05))
        n_next = int(math.ceil(n * grow))
        if n_next > MAX_ELEMENTS_CHOSEN:
            raise ValueError(
                f"accuracy: {tol:g} for {scope} needs more than {MAX_ELEMENTS_CHOSEN} "
                f"elements per blade: the mode {limiting} is still at an estimated "
                f"{worst:.2e} at {n} elements; ask for fewer modes (--count N, --max-hz F) or "
                "a larger tolerance")
        prev, n_prev, n = res, n, n_next


def _converge_p(run, n, tol, progress, in_scope, scope, order):
    """converge() for the p-version: at each mesh the estimate from order p - 1 on it; the
    elements raised by the law of order p - 1 (the estimate's), 1.25x to 2.5x a step."""
    while True:
        res = run(n)
        worst = attach_errors(run(n, order - 1), res, n, n, in_scope, (order - 1, order))
        limiting = res.settings["error_estimate"]["limiting_mode"]
        if progress is not None:
            progress(f"{n} elements of order {order}: largest estimated error {worst:.2e}"
                     + (f" ({limiting})" if limiting else ""))
        if worst <= tol:
            res.settings["accuracy"] = tol
            return res
        grow = min(2.5, max(1.25, (worst / tol) ** (1.0 / (2 * order - 2)) * 1.05))
        n_next = int(math.ceil(n * grow))
        if n_next * order > MAX_ELEMENTS_CHOSEN:
            raise ValueError(
                f"accuracy: {tol:g} for {scope} needs more than {MAX_ELEMENTS_CHOSEN} cells "
                f"per blade (elements x order {order}): the mode {limiting} is still at an "
                f"estimated {worst:.2e} at {n} elements; ask for fewer modes (--count N, "
                "--max-hz F) or a larger tolerance")
        n = n_next
