"""Curves of the generator search: energy against generator angle (the paper's Figs 8–10); a
fabric's shear curves are ``preform.shear.figures``."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from preform.base.figures import new_figure, save_figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

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
