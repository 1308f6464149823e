"""The polynomial energy as it was before its series form: the baseline of the ratios in
``bench_energy_series.py``, measured in the same process.

A frozen copy, reachable only from the benchmarks (never imported by preform or its tests):
``PiecewiseBranch`` integrating p·cos with the closed-form primitive S(x)·sin(x + b) +
S'(x)·cos(x + b), S = p − p″ + p⁗ − …, evaluated at x and at the piece's start and subtracted,
with Gauss–Legendre for whole pieces whose primitive was judged to cancel over their full width.
:func:`closed_form_path` builds every polynomial, tabulated and stitch law with it inside a
``with`` block.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator, Sequence

import numpy as np
from numpy.polynomial import polynomial as npoly
from numpy.typing import ArrayLike, NDArray

from preform.plugins.warpknit import shear as stitch_module
from preform.shear import laws as laws_module
from preform.shear.energy import (
    DOMAIN_END,
    Weight,
    _clamp_angle,
    _gauss_legendre,
    _horner,
    _non_negative_parts,
)

FloatArray = NDArray[np.float64]


def _cos_antiderivative(p: FloatArray) -> tuple[FloatArray, FloatArray]:
    s = np.array(p, dtype=float)
    term = np.array(p, dtype=float)
    sign = 1.0
    while True:
        term = npoly.polyder(term, 2) if term.size > 2 else np.zeros(1)
        if not np.any(term):
            break
        sign = -sign
        s = npoly.polyadd(s, sign * term)
    return s, npoly.polyder(s) if s.size > 1 else np.zeros(1)


class ClosedFormBranch:
    """``preform.shear.energy.PiecewiseBranch`` before the series form (same arguments)."""

    def __init__(
        self, breaks: Sequence[float], pieces: Sequence[ArrayLike], weight: Weight = "one"
    ) -> None:
        b = [float(v) for v in breaks]
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
        self._coef = np.zeros((len(polys), width + 1))
        for k, c in enumerate(polys):
            self._coef[k, : c.size] = c
        if weight == "one":
            anti = [npoly.polyint(c) for c in polys]
            self._anti = np.zeros((len(polys), width + 1))
            for k, a in enumerate(anti):
                self._anti[k, : a.size] = a
            self._anti_deriv = np.zeros((len(polys), 1))
        else:
            sp = [_cos_antiderivative(c) for c in polys]
            self._anti = np.zeros((len(polys), width + 1))
            self._anti_deriv = np.zeros((len(polys), width + 1))
            for k, (primitive_sin, primitive_cos) in enumerate(sp):
                self._anti[k, : primitive_sin.size] = primitive_sin
                self._anti_deriv[k, : primitive_cos.size] = primitive_cos
        edges = np.append(self.breaks, DOMAIN_END)
        widths = np.diff(edges)
        idx = np.arange(len(polys))
        self._quadrature = np.zeros(len(polys), dtype=bool)
        if weight == "cos":
            powers = widths[:, None] ** np.arange(width + 1)
            primitive_size = (np.abs(self._anti) + np.abs(self._anti_deriv)) * powers
            integrand_size = np.abs(self._coef) * powers
            self._quadrature = primitive_size.sum(axis=1) * 1e-7 > integrand_size.sum(
                axis=1
            ) * np.maximum(widths, 1e-300)
        self._gl_nodes, self._gl_weights = _gauss_legendre(width + 16)
        piece_integral = self._integral(idx, widths)
        self._cumulative = np.concatenate([[0.0], np.cumsum(piece_integral)])

    def _primitive(self, idx: NDArray[np.intp], x: FloatArray) -> FloatArray:
        if self.weight == "one":
            return _horner(self._anti, idx, x)
        angle = x + self.breaks[idx]
        return _horner(self._anti, idx, x) * np.sin(angle) + _horner(
            self._anti_deriv, idx, x
        ) * np.cos(angle)

    def _integral(self, idx: NDArray[np.intp], x: FloatArray) -> FloatArray:
        closed = self._primitive(idx, x) - self._primitive(idx, np.zeros_like(x))
        quad = np.ravel(self._quadrature[idx])
        if not np.any(quad):
            return closed
        out = np.array(closed, dtype=float).reshape(-1)
        rows, half = np.ravel(idx)[quad], 0.5 * np.ravel(x)[quad]
        local = (half[:, None] * (self._gl_nodes + 1.0)).ravel()
        rep = np.repeat(rows, self._gl_nodes.size)
        values = _horner(self._coef, rep, local) * np.cos(local + self.breaks[rep])
        out[quad] = half * (values.reshape(rows.size, -1) @ self._gl_weights)
        return out.reshape(np.shape(closed))

    def _locate(self, u: ArrayLike) -> tuple[NDArray[np.intp], FloatArray, FloatArray]:
        uu = _clamp_angle(u)
        idx = np.clip(np.searchsorted(self.breaks, uu, side="right") - 1, 0, self.breaks.size - 1)
        return idx, uu - self.breaks[idx], uu

    def magnitude(self, u: ArrayLike) -> FloatArray:
        idx, x, uu = self._locate(u)
        value = _horner(self._coef, idx, x)
        if self.weight == "cos":
            value = value * np.cos(uu)
        return np.maximum(value, 0.0)

    def energy(self, u: ArrayLike) -> FloatArray:
        idx, x, _ = self._locate(u)
        partial = self._integral(idx, x)
        return np.maximum(self._cumulative[idx] + partial, 0.0)


@contextlib.contextmanager
def closed_form_path() -> Iterator[None]:
    """Build polynomial, tabulated and stitch-polynomial branches with ``ClosedFormBranch``."""
    saved = (laws_module.PiecewiseBranch, stitch_module.PiecewiseBranch)
    laws_module.PiecewiseBranch = ClosedFormBranch  # type: ignore[misc,assignment]
    stitch_module.PiecewiseBranch = ClosedFormBranch  # type: ignore[misc,assignment]
    try:
        yield
    finally:
        laws_module.PiecewiseBranch, stitch_module.PiecewiseBranch = saved  # type: ignore[misc]
