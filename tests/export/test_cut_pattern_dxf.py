"""The cutting pattern's DXF as a CAD program reads it: ezdxf's auditor finds nothing to fix,
no layer holds an empty or degenerate drawing, and the label lies inside the piece it names
(its extents as ezdxf measures them with its font, and a monospaced box of one text height a
character, against the outline with shapely)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import ezdxf
import ezdxf.bbox
import numpy as np
import pytest
from shapely.geometry import LineString, Polygon, box

from preform.drape.engine.net import drape
from preform.drape.engine.ply import PlyOutline
from preform.export.cut_pattern import cut_pattern, write_cut_pattern_dxf, write_cut_pattern_svg
from preform.plugins.surfaces.basic import Hemisphere, Plane


def net(surface, ply_mm: tuple[float, float], alpha_deg: float):
    """A drape at d = 5 mm from the origin, the ply ``ply_mm`` [mm] a rectangle."""
    return drape(
        surface,
        start_xy_m=(0.0, 0.0),
        node_spacing_m=0.005,
        ply=PlyOutline.rectangle((1e-3 * ply_mm[0], 1e-3 * ply_mm[1])),
        generator_angle_rad=np.radians(alpha_deg),
    )


PLATE = Plane((1.0, 1.0))
CASES = {
    "hemisphere": (lambda: net(Hemisphere(0.1), (400, 400), 80.0), {}),
    "square plate": (lambda: net(PLATE, (200, 200), 90.0), {}),
    # a strip 400 mm by 30 mm: the old label (one line, height size/80) ran far past it
    "narrow strip": (lambda: net(PLATE, (400, 30), 70.0), {}),
    # split by a cut into a 100 mm and a 300 mm wide piece: the label goes in the larger
    "split plate": (
        lambda: net(PLATE, (400, 100), 90.0),
        {"cuts_mm": [((-100.0, -80.0), (-100.0, 80.0))]},
    ),
}


@pytest.fixture(scope="module", params=sorted(CASES))
def written(request, tmp_path_factory):
    make, options = CASES[request.param]
    result = make()
    pattern = cut_pattern(
        result,
        ply_name="E-BX-318, ply 2 of 6 (left door inner)",
        seam_allowance_mm=5.0,
        past_locking=np.zeros(result.valid.shape, dtype=bool),
        **options,
    )
    folder = tmp_path_factory.mktemp(request.param.replace(" ", "_"))
    write_cut_pattern_dxf(pattern, folder / "p.dxf")
    write_cut_pattern_svg(pattern, folder / "p.svg")
    return pattern, folder


def test_the_auditor_finds_nothing(written) -> None:
    _, folder = written
    doc = ezdxf.readfile(folder / "p.dxf")
    auditor = doc.audit()
    assert not auditor.has_errors, [str(e.message) for e in auditor.errors]
    assert not auditor.has_fixes, [str(f.message) for f in auditor.fixes]


def test_no_layer_draws_an_empty_or_degenerate_ring(written) -> None:
    """Nothing past locking: nothing on PAST_LOCKING (it once held a zero-size ring at the
    origin); every closed polyline encloses area."""
    pattern, folder = written
    assert pattern.past_locking is not None and pattern.past_locking.is_empty
    msp = ezdxf.readfile(folder / "p.dxf").modelspace()
    layers = [e.dxf.layer for e in msp]
    assert "PAST_LOCKING" not in layers
    for line in msp.query("LWPOLYLINE"):
        pts = [p[:2] for p in line.get_points()]
        if line.closed:
            assert len(set(pts)) >= 3 and Polygon(pts).area > 1.0, line.dxf.layer
    root = ET.parse(folder / "p.svg").getroot()
    assert not [p for p in root.iter() if p.attrib.get("id") == "past-locking"]


def test_the_label_lies_inside_its_piece(written) -> None:
    pattern, folder = written
    msp = ezdxf.readfile(folder / "p.dxf").modelspace()
    texts = [e for e in msp.query("TEXT") if e.dxf.layer == "LABELS"]
    assert [t.dxf.text for t in texts] == list(pattern.label_lines)
    assert "E-BX-318, ply 2 of 6" in texts[0].dxf.text
    piece = max(pattern.outline.geoms, key=lambda g: g.area)
    marks = [
        LineString([m.dxf.start.vec2, m.dxf.end.vec2])
        for m in msp.query("LINE")
        if m.dxf.layer == "FIBRE_MARKS"
    ]
    assert marks
    for text in texts:
        extents = ezdxf.bbox.extents([text])
        drawn = box(extents.extmin.x, extents.extmin.y, extents.extmax.x, extents.extmax.y)
        assert piece.contains(drawn), (text.dxf.text, drawn.bounds, piece.bounds)
        assert not any(drawn.intersects(mark) for mark in marks), text.dxf.text  # not struck out
        # a monospaced CAD font (a character and its spacing one text height wide) fits too
        h = text.dxf.height
        x, y = text.dxf.align_point.x, text.dxf.align_point.y
        half = 0.5 * len(text.dxf.text) * h
        assert piece.contains(box(x - half, y - 0.6 * h, x + half, y + 0.6 * h)), text.dxf.text
    # legible where there is room: the square plate's label is not shrunk to nothing
    assert pattern.text_height_mm >= min(2.0, 0.05 * piece.minimum_rotated_rectangle.length)


def test_the_label_is_as_large_as_fits_up_to_the_cap(written) -> None:
    """The fitted height is the largest the block allows at its centre: 5 % more and the block
    (one text height a character, 1.6 a line) leaves the piece, unless at the 10 mm cap."""
    pattern, _ = written
    piece = max(pattern.outline.geoms, key=lambda g: g.area)
    (x, y), h = pattern.label_at, pattern.text_height_mm
    chars, lines = max(len(line) for line in pattern.label_lines), len(pattern.label_lines)

    def block(height: float):
        half_w, half_h = 0.5 * chars * height, 0.5 * 1.6 * lines * height
        return box(x - half_w, y - half_h, x + half_w, y + half_h)

    assert piece.contains(block(h))
    assert h == pytest.approx(10.0) or not piece.contains(block(1.05 * h))
