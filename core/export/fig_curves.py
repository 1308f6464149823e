"""Curves of a fabric's shear behaviour and of the generator search (the paper's Figs 6, 8–10)."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.export.figures import new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

_SENSES = (
    ("positive", "positive shear (γ > 0)", "-", "#b2182b"),
    ("negative", "negative shear (γ < 0)", "--", "#2166ac"),
)


def _series(values: Any, name: str, n: int) -> np.ndarray:
    out = np.asarray(values, dtype=float).ravel()
    if out.shape != (n,):
        raise ValueError(f"{name} has {out.size} values, expected {n} (one per angle)")
    return out


def _columns(curves: Mapping[str, Any]) -> dict[str, Any]:
    """Turn per-angle rows of a sense into the column form this module draws."""
    out = dict(curves)
    for sense in ("positive", "negative"):
        rows = out.get(sense)
        if isinstance(rows, list) and rows and isinstance(rows[0], Mapping):
            out[sense] = {key: [row[key] for row in rows] for key in rows[0]}
    return out


def shear_curve_figure(
    curves: Mapping[str, Any],
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    size_px: tuple[int, int] = (1400, 600),
) -> Figure:
    """Shear force per unit length and shear strain energy against shear angle, both senses.

    ``curves`` is::

        {
            "angle_deg": [...],              # shear angle magnitude |γ| [deg]
            "positive": {                    # γ > 0 (warp-knit: parallel to the stitch)
                "force_N_per_mm": [...],     # F_s/L [N/mm], one per angle
                "energy_J_per_m2": [...],    # W(γ) [J/m²], one per angle
                "label": "parallel to stitch",   # optional legend text
                "angle_deg": [...],          # optional, overrides the shared angles
            },
            "negative": {...},               # γ < 0, same keys (values as magnitudes or signed)
            "locking_angle_deg": 52.0,       # optional, dotted vertical line
            "failure_angle_deg": 35.0,       # optional, dashed vertical line (stitch failure)
        }

    Either sense may be left out, and either quantity within a sense. Each sense may also be
    given as rows, as ``preform shear --json`` and the ``shear_curve`` step produce them:
    ``"positive": [{"angle_deg": .., "force_N_per_mm": .., "energy_J_per_m2": ..}, ...]``.
    Both senses are drawn against |γ|, as the paper plots them. Left panel force, right panel
    energy. Returns the figure (already saved).
    """
    curves = _columns(curves)
    fig = new_figure(size_px)
    force_ax, energy_ax = fig.subplots(1, 2)
    drawn = 0
    for sense, default_label, style, colour in _SENSES:
        data = curves.get(sense)
        if not data:
            continue
        angles = np.abs(np.asarray(data.get("angle_deg", curves.get("angle_deg", [])), dtype=float))
        label = str(data.get("label", default_label))
        for ax, key in ((force_ax, "force_N_per_mm"), (energy_ax, "energy_J_per_m2")):
            if key not in data:
                continue
            values = _series(data[key], f"{sense}.{key}", angles.size)
            # Negative-sense forces may come signed; the figure compares magnitudes.
            ax.plot(angles, np.abs(values), style, color=colour, lw=1.8, label=label)
            drawn += 1
    if drawn == 0:
        raise ValueError("curves has no 'positive' or 'negative' data to draw")
    for ax, ylabel, panel in (
        (force_ax, "shear force per unit length F$_s$/L [N/mm]", "Shear force"),
        (energy_ax, "shear strain energy W [J/m²]", "Shear strain energy"),
    ):
        _mark_angles(ax, curves)
        ax.set_xlabel("shear angle |γ| [deg]")
        ax.set_ylabel(ylabel)
        ax.set_title(panel)
        ax.set_xlim(left=0.0)
        ax.set_ylim(bottom=0.0)
        ax.grid(True, alpha=0.3)
        if ax.get_lines():
            ax.legend(fontsize="small", loc="upper left")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path)
    return fig


def _mark_angles(ax: Axes, curves: Mapping[str, Any]) -> None:
    for key, style, text in (
        ("locking_angle_deg", ":", "locking"),
        ("failure_angle_deg", "--", "stitch failure"),
    ):
        if curves.get(key) is not None:
            ax.axvline(float(curves[key]), ls=style, color="0.4", lw=1.0, label=text)


def energy_vs_angle_figure(
    curves: Mapping[str, Sequence[tuple[float, float]]],
    path: str | os.PathLike[str] | None,
    *,
    optima: Mapping[str, float] | None = None,
    title: str | None = None,
    size_px: tuple[int, int] = (900, 650),
) -> Figure:
    """Total shear strain energy [J] against generator angle [deg], one curve per fabric.

    ``curves`` maps a fabric name to (generator angle [deg], total energy [J]) pairs in any
    order; pairs with a non-finite energy (a failed drape) are left out. ``optima`` maps a
    fabric name to its optimum generator angle [deg], marked with a star on the curve and given
    in the legend. The energy axis turns logarithmic when the curves span more than a factor
    100 (locking at extreme angles). Returns the figure (already saved).
    """
    from matplotlib import colormaps

    if not curves:
        raise ValueError("curves is empty: nothing to draw")
    fig = new_figure(size_px)
    ax = fig.subplots()
    palette = colormaps["tab10" if len(curves) <= 10 else "tab20"]
    lowest, highest = np.inf, 0.0
    for n, (name, pairs) in enumerate(curves.items()):
        data = np.asarray(list(pairs), dtype=float).reshape(-1, 2)
        data = data[np.isfinite(data).all(axis=1)]
        data = data[np.argsort(data[:, 0])]
        colour = palette(n % palette.N)
        label = name
        if optima and name in optima:
            label = f"{name}: optimum {float(optima[name]):.1f}°"
        ax.plot(data[:, 0], data[:, 1], "-o", color=colour, ms=3, lw=1.5, label=label)
        if len(data):
            positive = data[:, 1][data[:, 1] > 0]
            if positive.size:
                lowest, highest = min(lowest, positive.min()), max(highest, positive.max())
        if optima and name in optima and len(data):
            best = float(optima[name])
            energy_at_best = float(np.interp(best, data[:, 0], data[:, 1]))
            ax.plot(best, energy_at_best, "*", color=colour, ms=16, mec="k")
            if len(curves) <= 3:  # labels beside the stars only while they cannot collide
                ax.annotate(
                    f"{best:.1f}°",
                    (best, energy_at_best),
                    textcoords="offset points",
                    xytext=(0, -18),
                    ha="center",
                    color=colour,
                )
    if np.isfinite(lowest) and highest / lowest > 100:
        # locking makes energies at extreme angles orders of magnitude larger than the optimum
        ax.set_yscale("log")
    ax.set_xlabel("generator angle α [deg]")
    ax.set_ylabel("total shear strain energy [J]")
    ax.set_title(title or "Total strain energy against generator angle")
    ax.grid(True, alpha=0.3, which="both")
    if len(curves) > 3:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.legend(fontsize="small")
    fig.tight_layout()
    if path is not None:  # None: the figure only (the Python API, a notebook)
        save_figure(fig, path)
    return fig


def fit_figure(
    curves: Mapping[str, Mapping[str, Any]],
    path: str | os.PathLike[str],
    *,
    title: str | None = None,
    size_px: tuple[int, int] = (900, 600),
) -> Figure:
    """A fitted shear law against the test data it was fitted to: F_s/L [N/mm] against |γ| [deg].

    ``curves`` maps a sense name to ``{"data": (angle_deg, force_N_per_mm), "fit": (angle_deg,
    force_N_per_mm), "label": str}``: the data as points, the fit as a line in the same colour.
    Returns the figure (already saved).
    """
    if not curves:
        raise ValueError("curves is empty: nothing to draw")
    fig = new_figure(size_px)
    ax = fig.subplots()
    colours = ("#b2182b", "#2166ac", "#1a9850", "#762a83")
    for n, (sense, spec) in enumerate(curves.items()):
        colour = colours[n % len(colours)]
        angle, force = (np.asarray(v, dtype=float) for v in spec["data"])
        ax.plot(angle, force, "o", color=colour, ms=3, alpha=0.5, label=f"{sense}: test data")
        grid, model = (np.asarray(v, dtype=float) for v in spec["fit"])
        ax.plot(grid, model, "-", color=colour, lw=2, label=str(spec.get("label", sense)))
    ax.set_xlabel("shear angle |γ| [deg]")
    ax.set_ylabel("shear force per unit length F$_s$/L [N/mm]")
    ax.set_xlim(left=0.0)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="upper left")
    ax.set_title(title or "Shear law fitted to test data")
    fig.tight_layout()
    save_figure(fig, path)
    return fig
