"""Strain energy per unit area W(u) = ∫_0^u M(g) dg of one sense ("branch") of a shear law.

A shear law is built from two branches, one per sense of shear (see ``preform.shear.law``). A
branch gives the torque magnitude M(u) ≥ 0 [N·m/m²] at the shear-angle magnitude u = |γ| [rad]
and its integral W(u) [J/m²]. Two exact-or-bounded ways to integrate are offered:

* ``PiecewiseBranch``: piecewise polynomials in u, optionally multiplied by cos u (the torque of
  a polynomial in F_s/L, since C = F_s·cos γ / L). The energy of each piece is one polynomial
  in the piece's local variable x with no constant term (zero at the piece's start): the
  antiderivative of p, or for p·cos that of p times the Taylor series of cos about the piece's
  start, cut where its remainder can no longer reach the last bit (``_cos_series_order``). Its
  terms are those of the integrand, so W is accurate to rounding relative to W itself at every
  angle, u → 0 and the ends of pieces included: within a few units in the last place times the
  cancellation already in p's own coefficients, Σ|c_k|x^k / p(x), which any evaluation from
  those coefficients carries. (The closed form S(x)·sin + S'(x)·cos, S = p − p″ + p⁗ − …,
  subtracts terms as large as p's high derivatives, 1e16 J/m² for a degree-7 force polynomial
  fitted in degrees, and lost every digit of W near zero shear.) Stretches where a polynomial
  dips below zero are set to zero by splitting at its real roots, so the clipped torque is
  integrated the same way.
* ``QuadratureBranch``: any vectorised magnitude function. A cumulative table of W at panel
  edges is built once with Gauss–Legendre quadrature; a query adds one more Gauss–Legendre rule
  from the nearest edge below, so no interpolation error is introduced. Points where the
  function's slope jumps must be passed as breakpoints (panels never straddle them). For a
  function smooth on each panel the error of an n-point rule on a panel of width h is bounded by
  h^(2n+1)(n!)^4 / ((2n+1)((2n)!)^3) · max|M^(2n)|; with the defaults (n = 8, h ≤ 0.5°) the
  relative error of W is below 1e-9 for the laws in preform (tested against closed forms and
  adaptive quadrature).

Angles beyond the domain end (90°: the two fibre families are parallel, no larger shear exists)
are clamped to it, so W stays finite and constant there.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Literal, Protocol

if TYPE_CHECKING:  # numpy is imported where a function computes: a listing needs none
    import numpy as np
    from numpy.typing import ArrayLike, NDArray

    FloatArray = NDArray[np.float64]


#: Largest shear-angle magnitude [rad] a branch is defined on (fibre families parallel).
DOMAIN_END = math.pi / 2

Weight = Literal["one", "cos"]


class Branch(Protocol):
    """Torque magnitude and strain energy of one sense of shear, over u = |γ| [rad]."""

    def magnitude(self, u: ArrayLike) -> FloatArray:
        """Torque magnitude M(u) ≥ 0 [N·m/m²] at shear-angle magnitudes u [rad]."""
        ...

    def energy(self, u: ArrayLike) -> FloatArray:
        """Strain energy W(u) = ∫_0^u M [J/m²] at shear-angle magnitudes u [rad]."""
        ...


def _clamp_angle(u: ArrayLike) -> FloatArray:
    import numpy as np

    return np.clip(np.abs(np.asarray(u, dtype=float)), 0.0, DOMAIN_END)


def _horner(coeffs: FloatArray, idx: NDArray[np.intp], x: FloatArray) -> FloatArray:
    """Evaluate row ``idx`` of an ascending-power coefficient matrix at local x, elementwise."""
    import numpy as np

    out = np.zeros_like(x)
    for k in range(coeffs.shape[1] - 1, -1, -1):
        out = out * x + coeffs[idx, k]
    return out


#: Bound on the cos series' truncation relative to W: 2⁻⁶⁴, 1/4096 of a unit in the last place
#: of a double, so the cut never shows above rounding.
_SERIES_TOLERANCE = 2.0**-64


def _cos_series_order(degree: int, width: float) -> int:
    """Least J for which cos(b + t) ≈ Σ_{j≤J} cos⁽ʲ⁾(b) t^j / j! leaves W within
    ``_SERIES_TOLERANCE`` of itself for a non-negative polynomial p of ``degree`` on a piece of
    ``width`` [rad] ending at or below 90°.

    Why this J suffices: the Taylor remainder is at most t^(J+1)/(J+1)! ≤ x·h^J/(J+1)! on
    [0, x], so the error of W(x) is at most that times ∫_0^x p. Below 90° cos(b + t) ≥
    (2/π)(π/2 − b − t) ≥ (2/π)(x − t), and for p ≥ 0 of degree d, ∫_0^x p(t)(x − t) dt ≥
    x·∫_0^x p / (d + 2)² (the least ratio over such p, the smallest eigenvalue of their moment
    problem, is 2 to 5.2 times this for d ≤ 15: tests/shear/test_energy_rounding.py), so W(x) ≥
    (2/π)·x·∫_0^x p / (d + 2)². Hence the relative error is at most (π/2)(d + 2)²·h^J/(J + 1)!.
    """
    bound_factor = 0.5 * math.pi * (degree + 2) ** 2
    order, power, factorial = 0, 1.0, 1.0
    while bound_factor * power / factorial > _SERIES_TOLERANCE:
        order += 1
        power *= width
        factorial *= order + 1
    return order


def _energy_polynomial(p: FloatArray, start: float, width: float, weight: Weight) -> FloatArray:
    """Ascending coefficients e of W(x) = x·Σ e_m x^m = ∫_0^x p(t)·w(start + t) dt [J/m²] on a
    piece beginning at ``start`` [rad], ``width`` [rad] wide, with w = 1 or cos."""
    import numpy as np
    from numpy.polynomial import polynomial as npoly

    if weight == "one":
        integrand = np.asarray(p, dtype=float)
    else:
        order = _cos_series_order(p.size - 1, width)
        # d^j/dt^j cos at the start cycles through cos, −sin, −cos, sin
        cycle = (math.cos(start), -math.sin(start), -math.cos(start), math.sin(start))
        taylor = np.array([cycle[j % 4] / math.factorial(j) for j in range(order + 1)])
        integrand = npoly.polymul(p, taylor)
    return np.asarray(integrand / np.arange(1, integrand.size + 1), dtype=float)


class PiecewiseBranch:
    """A non-negative piecewise polynomial torque magnitude, integrated exactly.

    ``breaks`` [rad] are ascending, start at 0 and end at or below 90°; the last piece extends to
    90°. ``pieces[k]`` holds ascending-power coefficients in the local variable x = u − breaks[k]
    [rad]; the magnitude is p_k(x) [N·m/m²] (``weight="one"``) or p_k(x)·cos(u) (``weight="cos"``).
    Negative stretches are replaced by zero before integrating (a fabric does not drive its own
    shear), so ``magnitude`` is never negative.
    """

    def __init__(
        self, breaks: Sequence[float], pieces: Sequence[ArrayLike], weight: Weight = "one"
    ) -> None:
        import numpy as np

        b = [float(v) for v in breaks]
        if len(b) != len(pieces) or not b or b[0] != 0.0:
            raise ValueError("breaks must start at 0 and give one start per piece")
        if any(b1 <= b0 for b0, b1 in itertools.pairwise(b)) or b[-1] >= DOMAIN_END:
            raise ValueError("breaks must be strictly ascending and below 90°")
        self.weight: Weight = weight
        starts: list[float] = []
        polys: list[FloatArray] = []
        ends = [*b[1:], DOMAIN_END]
        for start, end, coef in zip(b, ends, pieces, strict=True):
            for s, c in _non_negative_parts(np.atleast_1d(np.asarray(coef, float)), start, end):
                starts.append(s)
                polys.append(c)
        self.breaks = np.asarray(starts)
        width = max(c.size for c in polys)
        self._coef = np.zeros((len(polys), width))
        for k, c in enumerate(polys):
            self._coef[k, : c.size] = c
        widths = np.diff(np.append(self.breaks, DOMAIN_END))
        series = [
            _energy_polynomial(c, s, h, weight)
            for c, s, h in zip(polys, starts, widths, strict=True)
        ]
        #: Row k: W on piece k is x·Σ_m _energy[k, m]·x^m, x [rad] from the piece's start.
        self._energy = np.zeros((len(polys), max(e.size for e in series)))
        for k, e in enumerate(series):
            self._energy[k, : e.size] = e
        piece_energy = self._piece_energy(np.arange(len(polys)), widths)
        self._cumulative = np.concatenate([[0.0], np.cumsum(piece_energy)])

    def _piece_energy(self, idx: NDArray[np.intp], x: FloatArray) -> FloatArray:
        """∫_0^x of piece ``idx``'s magnitude in its local variable x [rad], elementwise [J/m²]."""
        return _horner(self._energy, idx, x) * x

    def _locate(self, u: ArrayLike) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        import numpy as np

        uu = _clamp_angle(u)
        idx = np.clip(np.searchsorted(self.breaks, uu, side="right") - 1, 0, self.breaks.size - 1)
        return idx, uu - self.breaks[idx], uu

    def magnitude(self, u: ArrayLike) -> FloatArray:
        """Torque magnitude M(u) ≥ 0 [N·m/m²] at shear-angle magnitudes u [rad]."""
        import numpy as np

        idx, x, uu = self._locate(u)
        value = _horner(self._coef, idx, x)
        if self.weight == "cos":
            value = value * np.cos(uu)
        return np.maximum(value, 0.0)

    def energy(self, u: ArrayLike) -> FloatArray:
        """Strain energy W(u) [J/m²], accurate to rounding relative to W(u) (module docstring)."""
        import numpy as np

        idx, x, _ = self._locate(u)
        return np.maximum(self._cumulative[idx] + self._piece_energy(idx, x), 0.0)


def _non_negative_parts(
    coef: FloatArray, start: float, end: float
) -> list[tuple[float, FloatArray]]:
    """Split p on [start, end) at its real roots; negative parts become the zero polynomial.

    Each part is returned as (its start, its coefficients in its own local variable).
    """
    import numpy as np
    from numpy.polynomial import polynomial as npoly

    length = end - start
    cuts = [0.0, length]
    # Drop leading-power coefficients too small to change p on this interval: they would only
    # send a root to infinity (or overflow the companion matrix).
    reach = max(length, 1.0) ** np.arange(coef.size)
    size = np.abs(coef) * reach
    significant = np.nonzero(size > 1e-14 * size.max())[0] if size.max() > 0 else np.array([0])
    trimmed = coef[: int(significant[-1]) + 1]
    if trimmed.size > 1:
        deriv = npoly.polyder(trimmed)
        for r in npoly.polyroots(trimmed):
            if abs(r.imag) > 1e-12 * max(1.0, abs(r.real)):
                continue
            # Companion-matrix roots carry an absolute error of ~eps·(largest root), so a small
            # root next to a huge one can be off by more than the gap to it; without polishing,
            # a negative stretch is kept and integrated, and W decreases. Newton polishes it.
            x = float(r.real)
            with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
                for _ in range(8):
                    slope = float(npoly.polyval(x, deriv))
                    if slope == 0.0:
                        break
                    step = x - float(npoly.polyval(x, trimmed)) / slope
                    if not abs(npoly.polyval(step, trimmed)) < abs(npoly.polyval(x, trimmed)):
                        break  # converged, or Newton would diverge (also catches inf/NaN)
                    x = step
            if 0.0 < x < length:
                cuts.append(x)
    cuts = sorted(set(cuts))
    parts: list[tuple[float, FloatArray]] = []
    # A sliver too short to keep joins the next part, which then starts where the sliver did:
    # dropping it would move the first break off 0 and make W(0) ≠ 0.
    sliver_start: float | None = None
    for a, b in itertools.pairwise(cuts):
        if b - a <= 1e-14 * max(1.0, length):
            sliver_start = a if sliver_start is None else sliver_start
            continue
        begin = a if sliver_start is None else sliver_start
        sliver_start = None
        shifted = shifted_polynomial(coef, begin)
        mid = npoly.polyval(0.5 * (a + b) - begin, shifted)
        parts.append((start + begin, shifted if mid >= 0.0 else np.zeros(1)))
    if not parts:
        parts.append((start, shifted_polynomial(coef, 0.0)))
    return parts


def shifted_polynomial(coef: FloatArray, a: float) -> FloatArray:
    """Coefficients of q(x) = p(x + a), ascending powers (p's ``coef`` ascending too)."""
    import numpy as np
    from numpy.polynomial import polynomial as npoly

    out = np.zeros(1)
    for c in coef[::-1]:
        out = npoly.polyadd(npoly.polymul(out, [a, 1.0]), [c])
    return np.asarray(out, dtype=float)


_GL_CACHE: dict[int, tuple[FloatArray, FloatArray]] = {}


def _gauss_legendre(order: int) -> tuple[FloatArray, FloatArray]:
    import numpy as np

    if order not in _GL_CACHE:
        nodes, weights = np.polynomial.legendre.leggauss(order)
        _GL_CACHE[order] = (np.asarray(nodes), np.asarray(weights))
    return _GL_CACHE[order]


class QuadratureBranch:
    """Torque magnitude from any vectorised function, energy by cumulative Gauss–Legendre.

    ``magnitude_of(u)`` [N·m/m²] must accept an array of any shape of angles u [rad] in
    [0, 90°] and return the same shape. ``breakpoints`` [rad] are angles where its slope jumps
    (e.g. a locking angle). ``panel_width`` [rad] and ``order`` set the accuracy (module
    docstring). The function is evaluated ``order`` times per queried angle.
    """

    def __init__(
        self,
        magnitude_of: Callable[[FloatArray], FloatArray],
        breakpoints: Sequence[float] = (),
        panel_width: float = math.radians(0.5),
        order: int = 8,
    ) -> None:
        import numpy as np

        if panel_width <= 0.0 or order < 1:
            raise ValueError("panel_width must be > 0 and order >= 1")
        self.magnitude_of = magnitude_of
        self.order = order
        inner = sorted({float(b) for b in breakpoints if 0.0 < b < DOMAIN_END})
        knots = [0.0, *inner, DOMAIN_END]
        edges: list[FloatArray] = []
        for a, b in itertools.pairwise(knots):
            n = max(1, math.ceil((b - a) / panel_width))
            edges.append(np.linspace(a, b, n + 1)[:-1])
        self.edges = np.append(np.concatenate(edges), DOMAIN_END)
        lo, hi = self.edges[:-1], self.edges[1:]
        panels = self._rule(lo, hi)
        self._cumulative = np.concatenate([[0.0], np.cumsum(panels)])

    def _rule(self, lo: FloatArray, hi: FloatArray) -> FloatArray:
        import numpy as np

        nodes, weights = _gauss_legendre(self.order)
        half = 0.5 * (hi - lo)
        points = (0.5 * (hi + lo))[..., None] + half[..., None] * nodes
        values = np.maximum(np.asarray(self.magnitude_of(points), dtype=float), 0.0)
        return half * (values @ weights)

    def magnitude(self, u: ArrayLike) -> FloatArray:
        """Torque magnitude M(u) ≥ 0 [N·m/m²] at shear-angle magnitudes u [rad]."""
        import numpy as np

        return np.maximum(np.asarray(self.magnitude_of(_clamp_angle(u)), dtype=float), 0.0)

    def energy(self, u: ArrayLike) -> FloatArray:
        """Strain energy W(u) [J/m²] (error bound in the module docstring)."""
        import numpy as np

        uu = _clamp_angle(u)
        idx = np.clip(np.searchsorted(self.edges, uu, side="right") - 1, 0, self.edges.size - 2)
        lo = self.edges[idx]
        return np.asarray(self._cumulative[idx] + self._rule(lo, uu), dtype=float)
