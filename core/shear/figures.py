"""Curves of a fabric's shear behaviour (the paper's Fig. 6), a fitted law against its test data,
a calibrated law against the measured curve."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from preform.base.figures import new_figure, save_figure

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


def calibration_figure(
    *,
    data: tuple[Any, Any],
    curves: Sequence[tuple[Any, Any, str]],
    path: str | os.PathLike[str],
    locking_deg: float | None = None,
    fit_range_deg: float | None = None,
    title: str | None = None,
    size_px: tuple[int, int] = (900, 600),
) -> Figure:
    """Measured F_s/L [N/mm] against γ [deg] as points, model curves ``(angle_deg,
    force_N_per_mm, label)`` as lines (the first bold), the locking angle and the end of the
    fit range as vertical lines. The y axis ends at twice the data's largest force, so a model
    many times stiffer than the data does not flatten them; a clipped model says so."""
    fig = new_figure(size_px)
    ax = fig.subplots()
    angle, force = (np.asarray(v, dtype=float) for v in data)
    ax.plot(angle, force, "o", color="black", ms=3.5, label="measured (normalised)")
    styles = (("-", 2.2, "#b2182b"), ("--", 1.4, "#2166ac"), (":", 1.4, "#1a9850"))
    top = 2.0 * float(np.max(np.abs(force))) if force.size else 1.0
    clipped = []
    for n, (grid, model, label) in enumerate(curves):
        line, width, colour = styles[n % len(styles)]
        g, m = np.asarray(grid, dtype=float), np.asarray(model, dtype=float)
        ax.plot(g, m, line, lw=width, color=colour, label=label)
        if np.any(m > top):
            clipped.append(label.split(":")[0])
    if locking_deg is not None:
        ax.axvline(locking_deg, color="grey", lw=1, ls="-.", label=f"locking {locking_deg:.1f}°")
    if fit_range_deg is not None:
        ax.axvline(fit_range_deg, color="grey", lw=0.8, ls=":", label="end of fit range")
    ax.set_ylim(bottom=min(0.0, float(np.min(force)) if force.size else 0.0), top=top)
    if clipped:
        ax.text(
            0.99,
            0.02,
            f"{len(clipped)} curve(s) rise above {top:.3g} N/mm, off the scale",
            transform=ax.transAxes,
            ha="right",
            va="bottom",
            fontsize="small",
            color="0.3",
        )
    ax.set_xlim(left=0.0)
    ax.set_xlabel("shear angle γ [deg]")
    ax.set_ylabel("shear force per unit length F$_s$/L [N/mm]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize="small", loc="upper left")
    ax.set_title(title or "Shear law calibrated on test data", fontsize="small")
    fig.tight_layout()
    save_figure(fig, path)
    return fig
