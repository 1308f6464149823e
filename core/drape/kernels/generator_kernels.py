"""Compiled steps of geodesic generator marching (``preform.drape.engine.generators``).

The marcher advances every half-line by one sub-step h at a time: straight on, back to the tool
along the normal at the current point (the discrete geodesic equation), then on to the next
node once the chord from the last node reaches d. Between the surface queries (the tool's own
``closest_point``/``normal``, or the compiled ones of a tool with compiled queries) the
arithmetic of a sub-step is these kernels, one pass over the running half-lines each; the
Python loop in ``preform.drape.engine.generators`` only calls them and the queries in turn. Imported
when a generator is marched, so numba stays out of start-up.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from preform.base.kernel_cache import cache_by_content

#: No other preform module is compiled into these kernels; the key they are cached under
#: is this file's (``preform.base.kernel_cache``).
COMPILED_IN: tuple[str, ...] = ()
cache_by_content(__name__)

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]
IntArray = NDArray[np.intp]

_jit = numba.njit(cache=True, error_model="numpy")


@_jit
def ahead(x: FloatArray, t: FloatArray, rows: IntArray, h: float) -> FloatArray:
    """x + h·t (len(rows), 3) [m]: one straight sub-step of the half-lines ``rows``."""
    out = np.empty((rows.shape[0], 3))
    for k in range(rows.shape[0]):
        i = rows[k]
        for c in range(3):
            out[k, c] = x[i, c] + h * t[i, c]
    return out


@_jit
def along_old_normal(
    straight: FloatArray, foot: FloatArray, n_foot: FloatArray, normal: FloatArray, rows: IntArray
):
    """The straight points moved along the normal at the current points (``normal[rows]``) by
    λ = (foot − point)·n_foot / (n·n_foot), which puts them on the foot's tangent plane; and
    where the tangent plane turns by more than 60° within the sub-step (a sharp crease, where
    λ is undefined) the straight point itself and a crease flag."""
    m = rows.shape[0]
    out = np.empty((m, 3))
    crease = np.empty(m, dtype=np.bool_)
    for k in range(m):
        i = rows[k]
        nn = normal[i, 0] * n_foot[k, 0] + normal[i, 1] * n_foot[k, 1] + normal[i, 2] * n_foot[k, 2]
        gap = (
            (foot[k, 0] - straight[k, 0]) * n_foot[k, 0]
            + (foot[k, 1] - straight[k, 1]) * n_foot[k, 1]
            + (foot[k, 2] - straight[k, 2]) * n_foot[k, 2]
        )
        crease[k] = abs(nn) < 0.5
        lam = 0.0 if crease[k] else gap / nn
        for c in range(3):
            out[k, c] = straight[k, c] + lam * normal[i, c]
    return out, crease


@_jit
def advance(
    rows: IntArray,
    x_new: FloatArray,
    dist: FloatArray,
    crease: BoolArray,
    n_foot: FloatArray,
    x: FloatArray,
    t: FloatArray,
    normal: FloatArray,
    last: FloatArray,
    running: BoolArray,
    h: float,
    spacing: float,
):
    """Take the sub-step to ``x_new`` (distance ``dist`` from the tool) on the half-lines
    ``rows``, in place on their point x, direction t (the unit step) and normal (the foot's).

    A half-line whose step makes less than h/2 of progress (along the old direction; its length
    across a crease) or lands more than h/2 from the tool has run past the tool's edge: it stops
    (``running`` False). Returns, per row, whether the step reaches chord ``spacing`` [m] from
    the last node, the point before the step, and the point of the straight step at that chord
    (the node's first guess)."""
    m = rows.shape[0]
    reach = np.zeros(m, dtype=np.bool_)
    before = np.empty((m, 3))
    guess = np.empty((m, 3))
    for k in range(m):
        i = rows[k]
        sx, sy, sz = x_new[k, 0] - x[i, 0], x_new[k, 1] - x[i, 1], x_new[k, 2] - x[i, 2]
        length = math.sqrt(sx * sx + sy * sy + sz * sz)
        if crease[k]:
            progress = length
        else:
            progress = sx * t[i, 0] + sy * t[i, 1] + sz * t[i, 2]
        if not math.isfinite(progress) or progress < 0.5 * h or dist[k] > 0.5 * h:
            running[i] = False
            continue
        wx, wy, wz = x[i, 0] - last[i, 0], x[i, 1] - last[i, 1], x[i, 2] - last[i, 2]
        rx, ry, rz = x_new[k, 0] - last[i, 0], x_new[k, 1] - last[i, 1], x_new[k, 2] - last[i, 2]
        before[k, 0], before[k, 1], before[k, 2] = x[i, 0], x[i, 1], x[i, 2]
        if rx * rx + ry * ry + rz * rz >= spacing * spacing:
            reach[k] = True
            # |w + τ·s| = d along the straight step s from x (w = x − last): the larger root
            ss = sx * sx + sy * sy + sz * sz
            ws = wx * sx + wy * sy + wz * sz
            ww = wx * wx + wy * wy + wz * wz
            tau = (-ws + math.sqrt(max(ws * ws - ss * (ww - spacing * spacing), 0.0))) / ss
            guess[k, 0] = x[i, 0] + tau * sx
            guess[k, 1] = x[i, 1] + tau * sy
            guess[k, 2] = x[i, 2] + tau * sz
        x[i, 0], x[i, 1], x[i, 2] = x_new[k, 0], x_new[k, 1], x_new[k, 2]
        t[i, 0], t[i, 1], t[i, 2] = sx / length, sy / length, sz / length
        normal[i, 0], normal[i, 1], normal[i, 2] = n_foot[k, 0], n_foot[k, 1], n_foot[k, 2]
    return reach, before, guess


@_jit
def to_chord(anchor: FloatArray, points: FloatArray, spacing: float) -> FloatArray:
    """``points`` moved along their direction from ``anchor`` to chord ``spacing`` [m]."""
    out = np.empty_like(points)
    for k in range(points.shape[0]):
        dx = points[k, 0] - anchor[k, 0]
        dy = points[k, 1] - anchor[k, 1]
        dz = points[k, 2] - anchor[k, 2]
        scale = spacing / math.sqrt(dx * dx + dy * dy + dz * dz)
        out[k, 0] = anchor[k, 0] + scale * dx
        out[k, 1] = anchor[k, 1] + scale * dy
        out[k, 2] = anchor[k, 2] + scale * dz
    return out
