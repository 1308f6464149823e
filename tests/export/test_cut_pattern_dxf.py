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
from shapely.geometry import LineString, Point, Polygon, box

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


def test_every_label_lies_inside_its_piece(written) -> None:
    pattern, folder = written
    msp = ezdxf.readfile(folder / "p.dxf").modelspace()
    texts = [e for e in msp.query("TEXT") if e.dxf.layer == "LABELS"]
    labels = pattern.drawn_labels
    assert [t.dxf.text for t in texts] == [line for label in labels for line in label.lines]
    assert texts[0].dxf.text.startswith("E-BX-318, ply 2 of 6")
    pieces = pattern.pieces_by_area
    # every piece is labelled here (the split plate's 100 mm piece too), each once
    assert sorted(label.piece for label in labels) == list(range(1, len(pieces) + 1))
    marks = [
        LineString([m.dxf.start.vec2, m.dxf.end.vec2])
        for m in msp.query("LINE")
        if m.dxf.layer == "FIBRE_MARKS"
    ]
    assert marks
    owner = [label.piece for label in labels for _ in label.lines]
    for text, k in zip(texts, owner, strict=True):
        piece = pieces[k - 1]
        extents = ezdxf.bbox.extents([text])
        drawn = box(extents.extmin.x, extents.extmin.y, extents.extmax.x, extents.extmax.y)
        assert piece.contains(drawn), (text.dxf.text, drawn.bounds, piece.bounds)
        assert not any(drawn.intersects(mark) for mark in marks), text.dxf.text  # not struck out
        # a monospaced CAD font (a character and its spacing one text height wide) fits too
        h = text.dxf.height
        x, y = text.dxf.align_point.x, text.dxf.align_point.y
        half = 0.5 * len(text.dxf.text) * h
        assert piece.contains(box(x - half, y - 0.6 * h, x + half, y + 0.6 * h)), text.dxf.text
        if len(pieces) > 1:
            assert h >= 2.0  # LABEL_MIN_HEIGHT_MM, legible
    # legible where there is room: the square plate's label is not shrunk to nothing
    piece = pieces[0]
    assert pattern.text_height_mm >= min(2.0, 0.05 * piece.minimum_rotated_rectangle.length)
    # the SVG draws the same lines, each tagged with its piece
    ns = {"s": "http://www.w3.org/2000/svg"}
    svg = ET.parse(folder / "p.svg").getroot().findall("s:text", ns)
    assert [(int(t.attrib["data-piece"]), t.text) for t in svg] == [
        (label.piece, line) for label in labels for line in label.lines
    ]


def test_a_piece_too_small_for_a_label_is_counted_not_drawn_over() -> None:
    """A plate cut into a 300 mm, a 94 mm and a 6 mm wide strip (100 mm tall): the first two
    get a label (the second "piece 2 of 3", clear of its fibre marks), the sliver none, and
    the pattern says so."""
    pattern = cut_pattern(
        net(PLATE, (400, 100), 90.0),
        ply_name="E-BX-318, ply 2",
        cuts_mm=[((-100.0, -80.0), (-100.0, 80.0)), ((-194.0, -80.0), (-194.0, 80.0))],
    )
    pieces = pattern.pieces_by_area
    widths = [round(p.bounds[2] - p.bounds[0]) for p in pieces]
    assert widths == [300, 94, 6]
    labelled = {label.piece: label for label in pattern.drawn_labels}
    assert sorted(labelled) == [1, 2] and pattern.unlabelled_pieces == 1
    assert labelled[2].lines == ("E-BX-318, ply 2", "piece 2 of 3")
    assert labelled[1].lines[:2] == ("E-BX-318, ply 2", "piece 1 of 3")
    assert pattern.summary()["unlabelled_pieces"] == 1
    assert pattern.summary()["labelled_pieces"] == 2
    assert any(pieces[1].contains(Point(m.start)) for m in pattern.marks)  # marks kept
    for k, label in labelled.items():
        assert pieces[k - 1].contains(Point(label.at))


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
