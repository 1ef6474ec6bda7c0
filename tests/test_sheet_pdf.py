"""prs_geom.exports.sheet_pdf: the PDF back end of the drawing sheets.

Path operators are checked against the Bezier closed forms, the file structure against
ISO 32000-1 (7.5: header, objects at the offsets the cross-reference table gives, trailer)
and against poppler's pdfinfo where it is installed, the line widths against the DXF
lineweights of the layers (ISO 128-20).
"""
import re
import shutil
import subprocess
import zlib

import numpy as np
import pytest
from ezdxf.addons.drawing.properties import BackendProperties
from ezdxf.math import Vec2
from ezdxf.npshapes import NumpyPath2d
from ezdxf.path import Path as EzPath

from prs_geom.exports.sheet import SHEET
from prs_geom.exports.sheet_pdf import MIN_LINE_WIDTH_MM, PdfSheetBackend, path_operators, pdf_document

_TOKEN = re.compile(r"(-?\d+) (-?\d+)|([mlch])\b")


def _segments(ops: str) -> list[tuple[str, np.ndarray]]:
    """(operator, its points in mm) in order, read from ``m``/``l``/``c``/``h`` operators."""
    out, pts = [], []
    for x, y, op in _TOKEN.findall(ops):
        if op:
            out.append((op, np.array(pts, dtype=float).reshape(-1, 2) / 1000.0))
            pts = []
        else:
            pts.append((int(x), int(y)))
    assert not pts
    return out


def test_quadratic_bezier_is_written_as_the_same_cubic():
    """A quadratic B(t) = (1-t)^2 p0 + 2t(1-t) c + t^2 p1 from ezdxf is written as a cubic
    whose points equal B(t) at t = 0, 0.1, ..., 1 to the 1 um of the coordinates."""
    p0, c, p1 = np.array([10.0, 20.0]), np.array([35.123, 80.456]), np.array([60.0, 25.5])
    path = EzPath(Vec2(p0))
    path.curve3_to(Vec2(p1), Vec2(c))
    path.line_to(Vec2(70.0, 30.0))
    seg = _segments(path_operators([NumpyPath2d(path)]))
    assert [op for op, _ in seg] == ["m", "c", "l"]
    assert np.allclose(seg[0][1], [p0], atol=5e-4)
    c1, c2, end = seg[1][1]
    t = np.linspace(0.0, 1.0, 11)[:, None]
    quad = (1 - t) ** 2 * p0 + 2 * t * (1 - t) * c + t ** 2 * p1
    cubic = (1 - t) ** 3 * p0 + 3 * t * (1 - t) ** 2 * c1 + 3 * t ** 2 * (1 - t) * c2 + t ** 3 * end
    assert np.abs(cubic - quad).max() < 2e-3
    assert np.allclose(seg[2][1], [[70.0, 30.0]], atol=5e-4)


def test_cubic_moves_and_several_paths_keep_their_points_in_order():
    a = EzPath(Vec2(1.0, 2.0))
    a.curve4_to(Vec2(7.0, 8.0), Vec2(3.0, 4.0), Vec2(5.0, 6.0))     # end, ctrl1, ctrl2
    a.move_to(Vec2(-1.5, 0.25))
    a.line_to(Vec2(0.0006, -0.0004))          # to the nearest um: (1, 0)
    b = EzPath(Vec2(100.0, 200.0))
    b.line_to(Vec2(100.0, 210.0))
    seg = _segments(path_operators([NumpyPath2d(a), NumpyPath2d(b)]))
    assert [op for op, _ in seg] == ["m", "c", "m", "l", "m", "l"]
    assert np.array_equal(seg[1][1], [[3.0, 4.0], [5.0, 6.0], [7.0, 8.0]])
    assert np.array_equal(seg[2][1], [[-1.5, 0.25]])
    assert np.array_equal(seg[3][1], [[0.001, 0.0]])
    assert np.array_equal(seg[4][1], [[100.0, 200.0]]) and np.array_equal(seg[5][1], [[100.0, 210.0]])


def test_backend_states_widths_colours_and_dots():
    be = PdfSheetBackend(SHEET)
    thick = BackendProperties(color="#000000", lineweight=0.5)
    hair = BackendProperties(color="#ff8000", lineweight=0.0)
    be.set_background("#ffffff")
    be.draw_line(Vec2(0, 0), Vec2(10, 0), thick)
    be.draw_solid_lines([(Vec2(1, 1), Vec2(2, 2)), (Vec2(5, 5), Vec2(5, 5))], hair)
    text = be.content().decode()
    assert text.startswith("q 0.0028346457 0 0 0.0028346457 0 0 cm 0 J 1 j\n") and text.endswith("Q\n")
    assert "1 1 1 rg 0 0 420000 297000 re f" in text          # the white A3 sheet
    assert "0 0 0 RG 500 w\n0 0 m 10000 0 l\nS" in text       # 0.5 mm at true width
    assert f"1 0.502 0 RG {round(MIN_LINE_WIDTH_MM * 1000)} w" in text   # a hairline at the minimum
    assert "1 J\n5000 5000 m 5000 5000 l\nS 0 J" in text     # a dot: round cap, zero length


def test_document_structure_and_offsets():
    """Header, one object per cross-reference entry at the offset it gives, the trailer's
    /Size and startxref, each page's MediaBox and its content stream inflating to what was
    given."""
    streams = [b"q 0 0 m 1000 1000 l S Q\n", b"q 1 0 0 rg 0 0 10 10 re f Q\n"]
    data = pdf_document([(SHEET, streams[0]), ((297.0, 210.0), streams[1])])
    assert data.startswith(b"%PDF-1.4\n") and data.endswith(b"%%EOF\n")
    start = int(re.search(rb"startxref\n(\d+)\n%%EOF", data).group(1))
    table = data[start:].split(b"trailer")[0].split(b"\n")
    assert table[0] == b"xref" and table[1] == b"0 8"
    offsets = [int(row[:10]) for row in table[3:10]]
    for number, offset in enumerate(offsets, start=1):
        assert data[offset:].startswith(f"{number} 0 obj\n".encode())
    assert b"/Size 8 /Root 1 0 R /Info 3 0 R" in data
    assert b"/MediaBox [0 0 1190.5512 841.8898]" in data and b"/MediaBox [0 0 841.8898 595.2756]" in data
    heads = list(re.finditer(rb"/Length (\d+) /Filter /FlateDecode >>\nstream\n", data))
    bodies = [data[h.end(): h.end() + int(h.group(1))] for h in heads]
    assert all(data[h.end() + int(h.group(1)):].startswith(b"\nendstream") for h in heads)
    assert [zlib.decompress(body) for body in bodies] == streams
    with pytest.raises(ValueError, match="at least one page"):
        pdf_document([])
    with pytest.raises(ValueError, match="creator"):
        pdf_document([(SHEET, b"")], creator="a (b")
    if shutil.which("pdfinfo"):
        path_info = subprocess.run(["pdfinfo", "-"], input=data, capture_output=True, check=True).stdout.decode()
        assert re.search(r"Pages:\s+2", path_info) and "1190.55 x 841.89 pts (A3)" in path_info


def test_drawing_sheet_draws_each_layer_at_its_iso_width():
    """A drawing sheet's page sets exactly the line widths of its layers' lineweights
    (prs_geom.exports.drawing.LAYERS: 0.18, 0.25, 0.35, 0.5 mm) and that of the frame."""
    import ezdxf  # noqa: F401  (the drawing module imports it lazily)
    from ezdxf.addons.drawing import Frontend, RenderContext
    from ezdxf.addons.drawing.config import BackgroundPolicy, ColorPolicy, Configuration

    from prs_geom.analysis.contact import analyse_contact
    from prs_geom.exports.drawing import LAYERS, build_drawing
    from prs_geom.model.design import PRSDesign

    d = PRSDesign()
    doc = build_drawing(d, analyse_contact(d), "roller", "2026-01-02", "test")
    be = PdfSheetBackend(SHEET)
    Frontend(RenderContext(doc), be, config=Configuration(background_policy=BackgroundPolicy.WHITE,
                                                          color_policy=ColorPolicy.BLACK)).draw_layout(
        doc.paperspace(), finalize=True)
    widths = {int(w) for w in re.findall(rb"RG (\d+) w", be.content())}
    layer_widths = {10 * lw for _, _, lw in LAYERS.values()}
    assert layer_widths <= widths, (layer_widths, widths)
    assert widths <= layer_widths | {250, 350, 500, 700}, widths   # ezdxf's default 0.25 mm, ISO series


def test_a_path_that_ends_where_it_starts_is_closed():
    """A closed outline gets h (a join at its first corner, not two butt ends, as a 0.5 mm
    outline showed at 1200 dpi); an open one and a fill's open subpath do not."""
    square = EzPath(Vec2(0.0, 0.0))
    for xy in ((10.0, 0.0), (10.0, 10.0), (0.0, 10.0), (0.0, 0.0)):
        square.line_to(Vec2(*xy))
    hook = EzPath(Vec2(20.0, 0.0))
    hook.line_to(Vec2(30.0, 0.0))
    hook.line_to(Vec2(30.0, 5.0))
    ops = [op for op, _ in _segments(path_operators([NumpyPath2d(square), NumpyPath2d(hook)]))]
    assert ops == ["m", "l", "l", "l", "l", "h", "m", "l", "l"]


def test_coordinates_beyond_a_pdf_integer_or_not_finite_are_refused():
    be = PdfSheetBackend(SHEET)
    props = BackendProperties()
    for bad in (float("nan"), float("inf"), 3.0e9):
        with pytest.raises(ValueError, match="not finite or beyond the PDF integer range"):
            be.draw_line(Vec2(0.0, 0.0), Vec2(bad, 1.0), props)


def test_a_segment_below_the_resolution_is_dropped_and_a_zero_one_is_a_dot():
    be = PdfSheetBackend(SHEET)
    be.draw_solid_lines([(Vec2(1.0, 1.0), Vec2(1.0004, 1.0)), (Vec2(2.0, 2.0), Vec2(2.0, 2.0)),
                         (Vec2(3.0, 3.0), Vec2(4.0, 3.0))], BackendProperties())
    text = be.content().decode()
    assert "1000 1000" not in text                          # 0.4 um long: not drawn
    assert "1 J\n2000 2000 m 2000 2000 l\nS 0 J" in text    # zero length: a dot
    assert "3000 3000 m 4000 3000 l\nS" in text
