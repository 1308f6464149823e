"""The report's interactive figures as plotly.js figure specifications (``{"data", "layout"}``).

Built as plain data, not with plotly's Python classes: the page needs only plotly.js (embedded
once, ``preform.report.render``), and a spec written here is the same text every time it is
built from the same folder. Units are in every axis title.
"""

from __future__ import annotations

from typing import Any

from preform.report.gather import CaseData, Net

#: Shear colour scale of the 3-D view (plotly's perceptually uniform "Viridis").
SHEAR_COLOURS = "Viridis"
_MARGIN = {"l": 60, "r": 20, "t": 40, "b": 50}


def _pairs(value: Any) -> list[tuple[float, float]]:
    """[[x, y], ...] from a summary, skipping anything that is not two numbers."""
    out = []
    if isinstance(value, list):
        for item in value:
            if (
                isinstance(item, list | tuple)
                and len(item) >= 2
                and all(isinstance(v, int | float) and not isinstance(v, bool) for v in item[:2])
            ):
                out.append((float(item[0]), float(item[1])))
    return out


def _plot_2d(
    data: list[dict[str, Any]], title: str, x_title: str, y_axis: dict[str, Any]
) -> dict[str, Any] | None:
    """A figure of curves against one axis, or None when there is no curve."""
    if not data:
        return None
    return {
        "data": data,
        "layout": {
            "title": {"text": title},
            "xaxis": {"title": {"text": x_title}},
            "yaxis": y_axis,
            "margin": _MARGIN,
            "height": 440,
            "hovermode": "closest",
        },
    }


def energy_vs_angle(scene: str, cases: list[CaseData]) -> dict[str, Any] | None:
    """E(α) of every fabric of a scene on one plot (the paper's Fig. 10), each optimum marked;
    an angle whose drape cannot be made (mostly wrinkle energy) drawn as an open marker."""
    data: list[dict[str, Any]] = []
    for case in sorted(cases, key=lambda c: c.material):
        curve = _pairs(case.summary.get("energy_vs_angle"))
        if not curve:
            continue
        table = case.summary.get("energy_vs_angle_table")
        makeable = {}
        if isinstance(table, list):
            for row in table:
                if isinstance(row, dict) and isinstance(row.get("generator_angle_deg"), float):
                    makeable[round(row["generator_angle_deg"], 6)] = row.get("makeable") is True
        symbols = ["circle" if makeable.get(round(a, 6), True) else "circle-open" for a, _ in curve]
        data.append(
            {
                "type": "scatter",
                "mode": "lines+markers",
                "name": case.material,
                "legendgroup": case.material,
                "x": [round(a, 4) for a, _ in curve],
                "y": [float(f"{e:.6g}") for _, e in curve],
                "marker": {"symbol": symbols, "size": 6},
                "hovertemplate": f"{case.material}<br>α = %{{x:.2f}}°<br>E = %{{y:.4g}} J"
                "<extra></extra>",
            }
        )
        angle = case.summary.get("optimum_generator_angle_deg")
        energy = case.summary.get("optimum_energy_J")
        if isinstance(angle, int | float) and isinstance(energy, int | float):
            data.append(
                {
                    "type": "scatter",
                    "mode": "markers",
                    "name": f"{case.material} optimum",
                    "legendgroup": case.material,
                    "showlegend": False,
                    "x": [round(float(angle), 4)],
                    "y": [float(f"{float(energy):.6g}")],
                    "marker": {"symbol": "star", "size": 13, "line": {"width": 1}},
                    "hovertemplate": f"{case.material} optimum<br>α = %{{x:.2f}}°<br>"
                    "E = %{y:.4g} J<extra></extra>",
                }
            )
    return _plot_2d(
        data,
        f"{scene}: strain energy against generator angle",
        "generator angle α (°)",
        {"title": {"text": "shear strain energy E (J)"}, "type": "log"},
    )


def shear_curves(scene: str, cases: list[CaseData], quantity: str) -> dict[str, Any] | None:
    """Shear curves of every fabric of a scene (the paper's Figs 8 and 9): ``quantity`` is
    ``force_N_per_mm`` (picture-frame force per unit side length) or ``energy_J_per_m2``; both
    senses against the size of the shear angle, the negative sense dashed."""
    titles = {
        "force_N_per_mm": ("shear force", "shear force per unit length (N/mm)"),
        "energy_J_per_m2": ("shear strain energy", "strain energy per unit area (J/m²)"),
    }
    title, axis = titles[quantity]
    data: list[dict[str, Any]] = []
    for case in sorted(cases, key=lambda c: c.material):
        curve = case.shear_curve or {}
        for sense, dash in (("positive", "solid"), ("negative", "dash")):
            points = curve.get(sense)
            if not isinstance(points, list):
                continue
            xs, ys = [], []
            for p in points:
                if isinstance(p, dict) and isinstance(p.get(quantity), int | float):
                    xs.append(round(abs(float(p.get("angle_deg", 0.0))), 4))
                    ys.append(float(f"{float(p[quantity]):.6g}"))
            if xs:
                data.append(
                    {
                        "type": "scatter",
                        "mode": "lines",
                        "name": f"{case.material} ({sense})",
                        "legendgroup": case.material,
                        "x": xs,
                        "y": ys,
                        "line": {"dash": dash},
                        "hovertemplate": f"{case.material}, {sense} sense<br>|γ| = %{{x:.1f}}°"
                        "<br>%{y:.4g}<extra></extra>",
                    }
                )
    return _plot_2d(
        data,
        f"{scene}: {title} against shear angle",
        "shear angle |γ| (°)",
        {"title": {"text": axis}},
    )


def drape_3d(case: CaseData, net: Net) -> dict[str, Any]:
    """The draped net in 3-D, coloured by shear angle; cells past a limit of the fabric (or
    folded) marked with crosses."""
    i, j, k = (list(t) for t in zip(*net.triangles, strict=True)) if net.triangles else ([], [], [])
    data: list[dict[str, Any]] = [
        {
            "type": "mesh3d",
            "name": "draped ply",
            "x": net.x_mm,
            "y": net.y_mm,
            "z": net.z_mm,
            "i": i,
            "j": j,
            "k": k,
            "intensity": net.shear_deg,
            "colorscale": SHEAR_COLOURS,
            "colorbar": {"title": {"text": "shear γ (°)"}},
            "flatshading": False,
            "hovertemplate": "x %{x:.1f} mm<br>y %{y:.1f} mm<br>z %{z:.1f} mm<br>"
            "γ = %{intensity:.1f}°<extra></extra>",
        }
    ]
    if net.marks:
        data.append(
            {
                "type": "scatter3d",
                "mode": "markers",
                "name": "wrinkle / fold / past a limit",
                "x": [m[0] for m in net.marks],
                "y": [m[1] for m in net.marks],
                "z": [round(m[2] + 0.5, 2) for m in net.marks],  # just above the surface
                "text": [m[3] for m in net.marks],
                "marker": {"symbol": "x", "size": 2.5, "color": "#d62728"},
                "hovertemplate": "%{text}<br>x %{x:.1f} mm, y %{y:.1f} mm<extra></extra>",
            }
        )
    return {
        "data": data,
        "layout": {
            "scene": {
                "aspectmode": "data",
                "xaxis": {"title": {"text": "x (mm)"}},
                "yaxis": {"title": {"text": "y (mm)"}},
                "zaxis": {"title": {"text": "z (mm)"}},
            },
            "margin": {"l": 0, "r": 0, "t": 30, "b": 0},
            "height": 520,
            "showlegend": bool(net.marks),
            "legend": {"x": 0, "y": 1},
            "title": {"text": f"{case.case_id}: draped ply coloured by shear"},
        },
    }


def tradeoff_plot(columns: list[str], rows: list[dict[str, str]]) -> dict[str, Any] | None:
    """preform bench tradeoff's table: wall time against error of each setting, when the table
    has the columns for it."""
    time_col, error_col = "wall_s", "energy_rel_error"
    if time_col not in columns or error_col not in columns:
        return None
    xs, ys, labels = [], [], []
    for row in rows:
        try:
            x, y = float(row[time_col]), float(row[error_col])
        except (TypeError, ValueError):
            continue
        if not (x > 0 and y > 0):  # log axes; the reference itself has no error
            continue
        xs.append(x)
        ys.append(y)
        labels.append(str(row.get("label") or row.get(columns[0]) or ""))
    if not xs:
        return None
    return {
        "data": [
            {
                "type": "scatter",
                "mode": "markers",
                "x": xs,
                "y": ys,
                "text": labels,
                "hovertemplate": "%{text}<br>%{x:.3g} s<br>error %{y:.3g}<extra></extra>",
            }
        ],
        "layout": {
            "title": {"text": "speed against accuracy of the fidelity settings"},
            "xaxis": {"title": {"text": "wall time of the study (s)"}, "type": "log"},
            "yaxis": {"title": {"text": "relative energy error (-)"}, "type": "log"},
            "margin": _MARGIN,
            "height": 420,
        },
    }
