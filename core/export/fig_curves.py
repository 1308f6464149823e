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


#: The energy axis ends at this multiple of the largest optimum energy: past locking, E(α) is
#: the law's continuation and climbs by orders of magnitude (10⁹ J at 30° for a 3D weave), which
#: on a log axis flattens the part of the curve that decides the optimum.
ENERGY_AXIS_FACTOR = 4.0
#: More fabrics than this go to the two-panel library figure.
MAX_CURVES_ON_ONE_AXIS = 4


def _sorted_finite(pairs: Sequence[tuple[float, float]]) -> np.ndarray:
    data = np.asarray(list(pairs), dtype=float).reshape(-1, 2)
    data = data[np.isfinite(data).all(axis=1)]
    return data[np.argsort(data[:, 0])]


def _note_clipped(ax: Axes, top: float, what: str) -> None:
    ax.text(
        0.99,
        0.02,
        f"{what} above {top:.3g} are off the scale\n(cells past locking: the law's "
        "continuation,\nnot a physical energy)",
        transform=ax.transAxes,
        ha="right",
        va="bottom",
        fontsize="small",
        color="0.3",
        bbox={"facecolor": "white", "edgecolor": "0.8", "alpha": 0.9},
    )


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
    in the legend. The energy axis is linear from 0 to ``ENERGY_AXIS_FACTOR`` times the largest
    optimum (or least) energy, so the region that decides the optimum fills the figure; what
    lies above is said on the figure. More than ``MAX_CURVES_ON_ONE_AXIS`` fabrics with their
    optima are drawn by :func:`library_energy_figure` (one axis cannot show them apart: the
    symmetric weaves' optima all lie at 90°). Saved to ``path`` unless None. Returns the figure.
    """
    from matplotlib import colormaps

    if not curves:
        raise ValueError("curves is empty: nothing to draw")
    if optima and len(curves) > MAX_CURVES_ON_ONE_AXIS and set(curves) <= set(optima):
        energies = {}
        for name, pairs in curves.items():
            data = _sorted_finite(pairs)
            if len(data):
                energies[name] = float(np.interp(float(optima[name]), data[:, 0], data[:, 1]))
        return library_energy_figure(
            curves,
            path,
            optima=optima,
            optimum_energies_J=energies,
            title=title,
            size_px=(max(size_px[0], 1400), max(size_px[1], 650)),
        )
    fig = new_figure(size_px)
    ax = fig.subplots()
    palette = colormaps["tab10" if len(curves) <= 10 else "tab20"]
    lows: list[float] = []
    clipped = False
    for n, (name, pairs) in enumerate(curves.items()):
        data = _sorted_finite(pairs)
        colour = palette(n % palette.N)
        label = name
        if optima and name in optima:
            label = f"{name}: optimum {float(optima[name]):.1f}°"
        ax.plot(data[:, 0], data[:, 1], "-o", color=colour, ms=3, lw=1.5, label=label)
        if not len(data):
            continue
        low = float(data[:, 1].min())
        if optima and name in optima:
            best = float(optima[name])
            low = float(np.interp(best, data[:, 0], data[:, 1]))
            ax.plot(best, low, "*", color=colour, ms=14, mec="k", zorder=4)
            if len(curves) <= 3:  # labels beside the stars only while they cannot collide
                ax.annotate(
                    f"{best:.1f}°",
                    (best, low),
                    textcoords="offset points",
                    xytext=(0, 10),
                    ha="center",
                    color=colour,
                )
        lows.append(low)
    if lows and max(lows) > 0:
        top = ENERGY_AXIS_FACTOR * max(lows)
        clipped = any(
            np.nanmax(_sorted_finite(p)[:, 1], initial=0.0) > top for p in curves.values()
        )
        ax.set_ylim(0.0, top)
        if clipped:
            _note_clipped(ax, top, "energies [J]")
    ax.set_xlabel("generator angle α [deg]")
    ax.set_ylabel("total shear strain energy [J]")
    ax.set_title(title or "Total strain energy against generator angle")
    ax.grid(True, alpha=0.3)
    if len(curves) > 3:
        ax.legend(fontsize="small", loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.legend(fontsize="small", loc="upper center")
    fig.tight_layout()
    if path is not None:  # None: the figure only (the Python API, a notebook)
        save_figure(fig, path)
    return fig


#: Relative energy E(α)/E(α*) shown on the library figure's left panel.
RELATIVE_AXIS_TOP = 3.0


def library_energy_figure(
    curves: Mapping[str, Sequence[tuple[float, float]]],
    path: str | os.PathLike[str] | None,
    *,
    optima: Mapping[str, float],
    optimum_energies_J: Mapping[str, float] | None = None,
    half_widths_deg: Mapping[str, float] | None = None,
    title: str | None = None,
    size_px: tuple[int, int] = (1400, 650),
) -> Figure:
    """The library-wide study (the paper's Fig. 10 for many fabrics), on two panels.

    Left: each fabric's E(α) divided by its least energy E* (so every curve has its minimum at
    1 and the shapes compare across fabrics whose energies differ tenfold), linear, up to
    ``RELATIVE_AXIS_TOP``. Right: the optimum generator angle α* [deg] of each fabric on its own
    row, with how well it is resolved (``half_widths_deg``, the search's bracket, as an error
    bar) and E* [J] beside it: fabrics that share an optimum (every symmetric weave at 90°) stay
    readable. ``curves`` as in :func:`energy_vs_angle_figure`; ``optima`` α* [deg] by fabric;
    ``optimum_energies_J`` E* [J] (default: the least energy of the curve). Saved to ``path``
    unless None. Returns the figure.
    """
    from matplotlib import colormaps

    if not curves:
        raise ValueError("curves is empty: nothing to draw")
    fig = new_figure(size_px)
    curve_ax, optimum_ax = fig.subplots(1, 2, gridspec_kw={"width_ratios": [1.6, 1.0]})
    palette = colormaps["tab10" if len(curves) <= 10 else "tab20"]
    names = list(curves)
    clipped = False
    for n, name in enumerate(names):
        data = _sorted_finite(curves[name])
        colour = palette(n % palette.N)
        if not len(data):
            continue
        energy = (optimum_energies_J or {}).get(name)
        if energy is None or not energy > 0:
            energy = float(data[:, 1].min())
        if not energy > 0:
            continue
        relative = data[:, 1] / energy
        clipped = clipped or bool(np.any(relative > RELATIVE_AXIS_TOP))
        curve_ax.plot(data[:, 0], relative, "-", color=colour, lw=1.6, label=name)
        best = optima.get(name)
        if best is not None:
            curve_ax.plot(float(best), 1.0, "|", color=colour, ms=14, mew=2.5)
            width = (half_widths_deg or {}).get(name)
            row = len(names) - 1 - n
            optimum_ax.errorbar(
                float(best),
                row,
                xerr=None if width is None else float(width),
                fmt="o",
                color=colour,
                ms=7,
                capsize=4,
            )
            optimum_ax.annotate(
                f"{float(best):.1f}°, E* = {energy:.3g} J",
                (float(best), row),
                textcoords="offset points",
                xytext=(9, 4),
                fontsize="small",
                color=colour,
            )
    curve_ax.set_ylim(0.9, RELATIVE_AXIS_TOP)
    if clipped:
        _note_clipped(curve_ax, RELATIVE_AXIS_TOP, "values of E/E*")
    curve_ax.axhline(1.0, color="0.6", lw=0.8, ls=":")
    curve_ax.set_xlabel("generator angle α [deg]")
    curve_ax.set_ylabel("total shear strain energy relative to its least, E(α)/E* [-]")
    curve_ax.set_title("Energy against generator angle (ticks: optima)")
    curve_ax.grid(True, alpha=0.3)
    curve_ax.legend(fontsize="small", loc="upper center", ncol=2, framealpha=0.9)
    optimum_ax.set_yticks(range(len(names)), list(reversed(names)), fontsize="small")
    optimum_ax.set_ylim(-0.7, len(names) - 0.3)
    optimum_ax.axvline(90.0, color="0.6", lw=0.8, ls=":")
    lo, hi = curve_ax.get_xlim()
    optimum_ax.set_xlim(lo, hi)
    optimum_ax.set_xlabel(
        "optimum generator angle α* [deg]"
        + (" (bar: the search's bracket)" if half_widths_deg else "")
    )
    optimum_ax.set_title("Least-energy generator angle and its energy E*")
    optimum_ax.grid(True, axis="x", alpha=0.3)
    fig.suptitle(title or "Total shear strain energy against generator angle")
    fig.tight_layout()
    if path is not None:
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
