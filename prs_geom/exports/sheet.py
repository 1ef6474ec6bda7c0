"""The A3 sheet every drawing shares (DXF, ezdxf): the paper's constants, the one pinned
font, the title block, the dimension style overrides, the scale label, and the
deterministic DXF writer.

The part drawings (:mod:`prs_geom.exports.drawing`), the mechanism drawings
(:mod:`prs_geom.exports.mechanism_drawing`) and the profile overview
(:mod:`prs_geom.exports.dxf`) are drawn on it. Paper coordinates are millimetres from the
sheet's lower left corner (ISO A3 landscape, ISO 5457 frame with a 20 mm filing margin);
text heights follow ISO 3098 (3.5 mm general, 5 mm titles).
"""
from __future__ import annotations

import functools
from pathlib import Path

__all__ = ["DRAWING_FONT", "FRAME", "GENERAL_TOLERANCES", "MIN_TEXT_H", "SHEET", "SURFACE_TEXTURE", "TEXT_H", "TITLE_BLOCK",
           "TITLE_H", "a3_paper_space", "dim_override", "drawing_number", "fitted_height", "iso7200_rows", "material_note", "part_notes", "pin_drawing_font", "save_dxf",
           "scale_text", "title_block", "use_drawing_font", "wrap_to_width"]

SHEET = (420.0, 297.0)                   # ISO A3 landscape (mm)
FRAME = (20.0, 10.0, 410.0, 287.0)       # border: 20 mm filing margin left, 10 mm elsewhere
TEXT_H = 3.5                             # ISO 3098 general text height on paper (mm)
TITLE_H = 5.0                            # ISO 3098 title text height on paper (mm)
#: The title block's paper rectangle (x0, y0, x1, y1), lower right of the frame.
TITLE_BLOCK = (230.0, 10.0, 410.0, 75.0)
#: The general tolerances every part sheet states: ISO 2768-1 class m for the linear and
#: angular sizes without a tolerance of their own, and for geometry ISO 22081's general
#: specification (ISO 2768-2, which the sheets would once have named, is withdrawn).
GENERAL_TOLERANCES = ("General tolerances: ISO 2768-1 m for linear and angular sizes; general geometrical "
                      "specification ISO 22081, 0.1 mm (ISO 2768-2 withdrawn)")
#: Surface texture by sheet (ISO 21920-1, Ra): ground thread flanks as for rolling contact,
#: gear flanks and fitted cylinders (journals, bores, seats) finish-turned or ground, the
#: rest turned.
SURFACE_TEXTURE = {
    "thread": "Ra 0.4 µm thread flanks; Ra 0.8 µm gear flanks, journals and seats; Ra 3.2 µm elsewhere",
    "carrier": "Ra 0.8 µm journal bores; Ra 1.6 µm faces; Ra 3.2 µm elsewhere",
    "nut_end": "Ra 0.8 µm bore over the ring gear; Ra 1.6 µm groove; Ra 3.2 µm elsewhere",
}
#: The one font of every drawing's texts and dimensions: DejaVu Sans, which matplotlib ships,
#: so the PDF and ezdxf's text boxes are the same on every machine (a DXF reader without it
#: substitutes its own).
DRAWING_FONT = "DejaVuSans.ttf"


@functools.cache
def pin_drawing_font() -> str:
    """Make :data:`DRAWING_FONT` known to ezdxf's font manager (from matplotlib's font
    folder, whatever the system has installed) and return its name. ezdxf measures and
    renders a text style's font by file name through that manager, and falls back to another
    installed font when the name is unknown.

    The folder is found without importing matplotlib (its ``get_data_path()`` is the
    package's ``mpl-data``): a build's main process writes DXF files but draws nothing, and
    the import would cost it 0.2 s and 30 MB."""
    import importlib.util

    from ezdxf.fonts import fonts

    spec = importlib.util.find_spec("matplotlib")
    if spec is None or not spec.submodule_search_locations:   # pragma: no cover - a core dependency
        raise FileNotFoundError("matplotlib, whose fonts the drawings use, is not installed")
    folder = Path(next(iter(spec.submodule_search_locations))) / "mpl-data" / "fonts" / "ttf"
    if not (folder / DRAWING_FONT).is_file():     # pragma: no cover - matplotlib always ships it
        raise FileNotFoundError(f"matplotlib's {DRAWING_FONT} is missing from {folder}")
    fonts.font_manager.scan_folder(folder)
    return DRAWING_FONT


def use_drawing_font(doc) -> None:
    """Every text style of ``doc`` on :data:`DRAWING_FONT` and every dimension style's text
    in the Standard style: one font for all the drawing's texts."""
    font = pin_drawing_font()
    for style in doc.styles:
        style.dxf.font = font
    for dimstyle in doc.dimstyles:
        dimstyle.dxf.dimtxsty = "Standard"


def dim_override(scale: float, decimals: int = 4) -> dict:
    """Dimension style override for text of TEXT_H on paper at a view scale ``scale``."""
    return {"dimscale": 1.0 / scale, "dimtxt": TEXT_H, "dimasz": 2.5, "dimexo": 1.0, "dimexe": 1.5,
            "dimgap": 0.8, "dimdec": decimals, "dimadec": decimals, "dimzin": 0, "dimazin": 0, "dimlfac": 1.0,
            "dimtad": 1, "dimdsep": 46, "dimclrd": 3, "dimclre": 3, "dimclrt": 3}


def scale_text(s: float) -> str:
    """The scale as drawings print it: "2:1", "1:1", "1:2"."""
    return f"{s:g}:1" if s >= 1 else f"1:{1 / s:g}"


#: The smallest text height on paper (mm): ISO 3098's smallest nominal height.
MIN_TEXT_H = 2.5


def fitted_height(text: str, width_mm: float, height_mm: float = TEXT_H) -> float:
    """The text height (mm) for ``text`` in ``width_mm`` (:data:`DRAWING_FONT`, ezdxf's font
    metrics): ``height_mm`` when it fits there, else :data:`MIN_TEXT_H` (never smaller: a
    text that does not fit at that height is wrapped, :func:`wrap_to_width`)."""
    from ezdxf.fonts import fonts

    wide = fonts.make_font(pin_drawing_font(), height_mm, 1.0).text_width(text)
    return height_mm if wide <= width_mm else MIN_TEXT_H


def a3_paper_space(doc, name: str, frame_layer: str = "TITLE"):
    """``doc``'s paper space renamed ``name``, set up as an A3 landscape page (no margins,
    mm) with the :data:`FRAME` drawn 0.7 mm wide on ``frame_layer``; returned."""
    psp = doc.layouts.get("Layout1")
    doc.layouts.rename("Layout1", name)
    psp.page_setup(size=SHEET, margins=(0, 0, 0, 0), units="mm", name="ISO_A3_(420.00_x_297.00_MM)")
    fx0, fy0, fx1, fy1 = FRAME
    psp.add_lwpolyline([(fx0, fy0), (fx1, fy0), (fx1, fy1), (fx0, fy1)], close=True,
                       dxfattribs={"layer": frame_layer, "const_width": 0.7})
    return psp


def title_block(psp, rows: list[tuple[str, str]], title: str) -> None:
    """The title block in paper space ``psp``: ``title`` on its top line, then ``rows``
    (key, value) two to a line, "key: value" each, 3.5 mm high where it fits its cell, else
    2.5 mm and wrapped within the cell (:func:`fitted_height`, :func:`wrap_to_width`)."""
    x0, y0, x1, y1 = TITLE_BLOCK
    psp.add_lwpolyline([(x0, y0), (x1, y0), (x1, y1), (x0, y1)], close=True, dxfattribs={"layer": "TITLE"})
    row_h = (y1 - y0 - 10.0) / ((len(rows) + 1) // 2)
    psp.add_line((x0, y1 - 10.0), (x1, y1 - 10.0), dxfattribs={"layer": "TITLE"})
    psp.add_text(title, height=TITLE_H, dxfattribs={"layer": "TITLE"}).set_placement((x0 + 2.0, y1 - 7.5))
    xm = 0.5 * (x0 + x1)
    psp.add_line((xm, y0), (xm, y1 - 10.0), dxfattribs={"layer": "TITLE"})
    for i, (key, val) in enumerate(rows):
        col, row = i % 2, i // 2
        yy = y1 - 10.0 - (row + 1) * row_h
        if row:
            psp.add_line((x0, yy + row_h), (x1, yy + row_h), dxfattribs={"layer": "TITLE"})
        text, cell = f"{key}: {val}", xm - x0 - 3.0
        height = fitted_height(text, cell)
        lines = [text] if height > MIN_TEXT_H else wrap_to_width(text, cell, MIN_TEXT_H)
        for j, line in enumerate(lines):
            psp.add_text(line, height=height, dxfattribs={"layer": "TITLE"}).set_placement(
                (x0 + 1.5 + col * (xm - x0), yy + 0.3 * row_h + (len(lines) - 1 - j) * (height + 1.5)))


def drawing_number(design, index: int) -> str:
    """The drawing's identification number (ISO 7200): the design's name in capitals and
    digits (other characters as "-", at most 24, "PRS" when none is left) and the sheet's
    index, e.g. ``DEFAULT-01``. It stays with the design through its revisions."""
    import re

    stem = re.sub(r"[^A-Za-z0-9]+", "-", design.name).strip("-").upper()[:24].strip("-") or "PRS"
    return f"{stem}-{index:02d}"


def iso7200_rows(design, part: str, material, scale: str, date: str, version: str, index: int,
                 sheets: int, kind: str = "Detail drawing") -> list[tuple[str, str]]:
    """The title block's data fields (ISO 7200): design and part, material grade and heat
    treatment, identification number (:func:`drawing_number`) and revision (the design hash:
    a changed design is a new revision), document type, scale, date of issue, creator,
    design sha256 and the sheet number n/N."""
    from prs_geom.exports.textsafe import dxf_text
    from prs_geom.model.io import design_hash

    h = design_hash(design)
    # the grade where the design gives one, else the material's name (the notes say what to set)
    grade = dxf_text(material.grade) if material.grade else dxf_text(material.name)
    treatment = dxf_text(material.heat_treatment) if material.heat_treatment else "none specified"
    return [("Design", dxf_text(design.name)), ("Part", part), ("Material", grade), ("Heat treatment", treatment),
            ("Drawing no.", drawing_number(design, index)), ("Revision", h[:8]), ("Document type", kind),
            ("Scale", scale), ("Date of issue", date), ("Creator", f"prs_geom {version}"),
            ("Design sha256", h), ("Sheet", f"{index}/{sheets} A3")]


def save_dxf(doc, path: Path) -> None:
    """Save ``doc`` with its CLASSES section in a fixed order.

    ezdxf registers the classes of the entity types in use by iterating a set, so their
    order (and the file's bytes) would change with Python's string-hash seed from run to
    run; registering them here first, required ones in ezdxf's order and the rest sorted,
    makes the same drawing give the same file.
    """
    from ezdxf.sections.classes import REQ_R2004, REQUIRED_CLASSES

    for name in REQUIRED_CLASSES.get(doc.dxfversion, REQ_R2004):
        doc.classes.add_class(name)
    for name in sorted(doc.entitydb.dxf_types_in_use()):
        doc.classes.add_class(name)
    doc.saveas(path)


def material_note(material, field: str) -> str:
    """The sheet's material line: name, grade and heat treatment of ``material``
    (:class:`~prs_geom.model.design.Material`), each design text made literal for DXF;
    ``field`` is the design-file path of the material (``materials.carrier``), named where a
    grade or a heat treatment is not specified."""
    from prs_geom.exports.textsafe import dxf_text

    grade = dxf_text(material.grade) if material.grade else f"grade not specified ({field}.grade)"
    treatment = dxf_text(material.heat_treatment) if material.heat_treatment else "none specified"
    return f"Material: {dxf_text(material.name)}, {grade}; heat treatment: {treatment}"


def part_notes(material, field: str, texture: str) -> list[str]:
    """The notes every part sheet carries: material (:func:`material_note`), general
    tolerances (:data:`GENERAL_TOLERANCES`) and surface texture (``texture``, a key of
    :data:`SURFACE_TEXTURE`)."""
    return [material_note(material, field), GENERAL_TOLERANCES,
            f"Surface texture (ISO 21920-1): {SURFACE_TEXTURE[texture]}"]


def wrap_to_width(text: str, width_mm: float, height_mm: float, indent: str = "  ") -> list[str]:
    """``text`` wrapped (:func:`~prs_geom.exports.textsafe.dxf_wrap`, never inside a DXF
    escape) into lines no wider than ``width_mm`` in :data:`DRAWING_FONT` at the text height
    ``height_mm``, measured with ezdxf's font metrics (the raw string, so an escape such as
    ``%%c`` counts wider than its sign: the lines only err short)."""
    from ezdxf.fonts import fonts

    from prs_geom.exports.textsafe import dxf_wrap

    font = fonts.make_font(pin_drawing_font(), height_mm, 1.0)
    for chars in range(max(len(text), 10), 9, -1):
        lines = dxf_wrap(text, chars, subsequent_indent=indent)
        if max(font.text_width(line) for line in lines) <= width_mm:
            return lines
    return dxf_wrap(text, 10, subsequent_indent=indent)
