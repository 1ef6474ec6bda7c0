"""The parts list (bill of materials): ``parts_list.csv``, ``parts_list.xlsx`` and the table
of report.html.

One row per distinct part: item number (the balloon number of the assembly drawing), part,
quantity, material and density (``materials.*`` of the design), the volume of one piece
(:func:`prs_geom.mesh.volumes.part_volumes`: from the meshes of its rigid body, a roller
with its gears and journals, the nut with its ring gears, ends and flange, the screw with
its ends), the mass of one piece (density x volume) and the standard designation where
there is one (the DIN 472 retaining ring). Masses are in kg, volumes in mm^3; the CSV keeps
full float64 precision.

An actuator (:func:`prs_geom.geometry.actuator.actuator_layout`) adds its purchased parts:
the bearings of each screw end, the KM locknut, the DIN 471 ring, the flange bolts (length
by the actuator layout's rule) and the drive key, each with its catalogue designation.
Their material reads :data:`PURCHASED`; density, volume and masses are empty (None in
report.json): a catalogue part's mass is the supplier's, not a mesh's.

The material names come from the design file as typed: they go through
:mod:`prs_geom.exports.textsafe` (a CSV field never begins a spreadsheet formula, every text
cell of the workbook is stored as a string).
"""
from __future__ import annotations

import csv
import io
import math
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

from prs_geom.exports.textsafe import csv_comment, csv_field, xlsx_append

__all__ = [
    "COLUMNS", "PURCHASED", "PartItem", "PartsListRow", "part_items", "parts_list", "parts_list_csv", "read_parts_list_csv",
    "read_parts_list_xlsx", "total_mass_kg", "write_parts_list_xlsx",
]

#: The material column of a purchased (catalogue) part.
PURCHASED = "purchased"

#: Columns: key, title, unit.
COLUMNS = (("item", "item", ""), ("part", "part", ""), ("quantity", "quantity", ""),
           ("material", "material", ""), ("density_kg_m3", "density", "kg/m^3"),
           ("volume_mm3", "volume of one", "mm^3"), ("mass_kg", "mass of one", "kg"),
           ("total_mass_kg", "mass of all", "kg"), ("designation", "standard designation", ""),
           ("description", "description", ""))


@dataclass(frozen=True)
class PartsListRow:
    """One line of the parts list (see the module docstring for units)."""

    item: int
    part: str
    quantity: int
    material: str
    #: None for a purchased part (no mesh volume, no mass)
    density_kg_m3: float | None
    volume_mm3: float | None
    designation: str
    description: str

    @property
    def mass_kg(self) -> float | None:
        if self.density_kg_m3 is None or self.volume_mm3 is None:
            return None
        return self.density_kg_m3 * self.volume_mm3 * 1e-9

    @property
    def total_mass_kg(self) -> float | None:
        mass = self.mass_kg
        return None if mass is None else self.quantity * mass

    def as_dict(self) -> dict[str, Any]:
        return {**asdict(self), "mass_kg": self.mass_kg, "total_mass_kg": self.total_mass_kg}


@dataclass(frozen=True)
class PartItem:
    """A parts-list line without its mass: what a drawing's balloons and table need."""

    item: int
    part: str
    quantity: int
    material: Any          # prs_geom.model.design.Material; None for a purchased part
    designation: str
    description: str
    #: the rigid body (scene name) whose volume is one piece's; None for a purchased part
    body: str | None
    #: a purchased part modelled as an envelope: the scene name of its first copy (None when
    #: it is not modelled, like the bolts and the key)
    envelope: str | None = None

    @property
    def purchased(self) -> bool:
        """A catalogue part: no material of the design, no mesh volume."""
        return self.body is None


#: One parts-list line before numbering: part, quantity, material (None: purchased),
#: designation, description, rigid body (None: purchased)[, envelope's scene name].
_Row = tuple[Any, ...]


def part_items(design: Any) -> list[PartItem]:
    """The items of the parts list of ``design``, numbered in order: screw, roller, nut and,
    with the mechanism parts, carrier and retaining ring (the DIN 472 designation); then an
    actuator's purchased parts (:func:`_actuator_rows`)."""
    from prs_geom.geometry.actuator import actuator_layout
    from prs_geom.geometry.frames import screw_thread_length
    from prs_geom.geometry.mechanism import layout

    mats = design.materials
    d = design
    hand = d.thread.hand
    act = actuator_layout(design)
    screw_extra = nut_extra = ""
    if act is not None:
        fixed = act.ends[0] if act.fixed_side < 0 else act.ends[1]
        drive = "keyway" if fixed.key is not None else "flat"
        screw_extra = (f", overall length {act.screw_length_mm:g} mm with bearing seats, locknut thread and "
                       f"drive journal with {drive}")
        if act.nut_mount.kind == "flange":
            nut_extra = f", flange with {act.nut_mount.bolt_count} bolt holes"
    rows: list[_Row] = [
        ("screw", 1, mats.screw, "",
         f"screw, {d.screw.starts}-start {hand}-hand thread, pitch {d.thread.pitch_mm:g} mm, "
         f"pitch diameter {d.screw.pitch_diameter_mm:g} mm, threaded length {screw_thread_length(d):g} mm"
         + screw_extra, "screw"),
        ("roller", d.roller.count, mats.roller, "",
         f"roller, single-start {hand}-hand thread, pitch diameter {d.roller.pitch_diameter_mm:g} mm, "
         f"end gears and journals", "roller_0"),
        ("nut", 1, mats.nut, "",
         f"nut, {d.nut.starts}-start {hand}-hand internal thread, outside diameter {d.nut.outer_diameter_mm:g} mm, "
         f"ring gears and retaining-ring grooves at both ends" + nut_extra, "nut"),
    ]
    lay = layout(design)
    if lay is not None:
        rows.append(("carrier", 2, mats.carrier, "", f"carrier ring with {d.roller.count} journal bores", "carrier_lo"))
        rows.append(("retaining ring", 2, mats.retaining_ring, lay.ring.designation,
                     "internal retaining ring for bores", "retaining_ring_lo"))
    if act is not None:
        rows += _actuator_rows(act)
    fields = ("part", "quantity", "material", "designation", "description", "body", "envelope")
    return [PartItem(item=i, **dict(zip(fields, row))) for i, row in enumerate(rows, start=1)]


def _actuator_rows(act: Any) -> list[_Row]:
    """The purchased parts of an actuator layout: per screw end its bearings (the fixed
    end's pair as one line of two), the KM locknut, the DIN 471 ring; the flange bolts and
    the drive key."""
    rows: list[_Row] = []
    for end in act.ends:
        if end.bearings:
            b = end.bearings[0]
            kind = ("angular contact ball bearing, a pair back to back" if end.role == "fixed"
                    else "deep groove ball bearing, free to slide in its housing")
            rows.append((f"bearing, {end.role} end", len(end.bearings), None, b.designation,
                         f"{kind}; d x D x B = {b.size.bore_mm:g} x {b.size.outer_diameter_mm:g} x "
                         f"{b.size.width_mm:g} mm (ISO 15); {PURCHASED}", None, f"bearing_{end.role}_0"))
    for end in act.ends:
        if end.locknut is not None:
            rows.append(("locknut", 1, None, end.locknut.designation,
                         f"precision locknut (ISO 2982-2), thread {end.locknut.thread} {end.locknut_tolerance} on the "
                         f"screw, clamps the {end.role} end's bearings; {PURCHASED}", None, "locknut"))
        if end.ring is not None:
            rows.append(("shaft ring", 1, None, end.ring.designation,
                         f"retaining ring for shafts (DIN 471), holds the {end.role} end's bearing; {PURCHASED}", None,
                         "shaft_ring"))
    m = act.nut_mount
    if m.kind == "flange" and m.bolt is not None:
        rule = act.sizes["actuator.nut_mount.bolt_length_mm"].source
        rows.append(("flange bolt", m.bolt_count, None, f"ISO 4762 {m.bolt.name} x {m.bolt_length_mm:g} - 8.8",
                     f"socket head cap screw, nut flange to housing; length: {rule}; {PURCHASED}", None,
                     "flange_bolt_0"))
    key = act.sizes.get("actuator.drive.key")
    if key is not None:
        rows.append(("drive key", 1, None, str(key.value),
                     f"parallel key (DIN 6885-1 form A) in the drive journal's keyway; {PURCHASED}", None,
                     "drive_key"))
    return rows


def parts_list(design: Any, volumes: Mapping[str, float]) -> list[PartsListRow]:
    """The rows of the parts list of ``design``; ``volumes``: the volume (mm^3) of one piece
    of every rigid body, by body name (:func:`prs_geom.mesh.volumes.part_volumes`). A
    purchased part's material reads :data:`PURCHASED`, its density and volume None."""
    return [PartsListRow(item=it.item, part=it.part, quantity=it.quantity,
                         material=PURCHASED if it.purchased else it.material.name,
                         density_kg_m3=None if it.purchased else it.material.density_kg_m3,
                         volume_mm3=None if it.purchased else volumes[it.body],
                         designation=it.designation, description=it.description) for it in part_items(design)]


def _cell(v: Any) -> str:
    """A CSV field: text neutralised (:func:`~prs_geom.exports.textsafe.csv_field`), floats
    in full precision, None (a purchased part's mass) empty."""
    if v is None:
        return ""
    if isinstance(v, str):
        return csv_field(v)
    return repr(v) if isinstance(v, float) else str(v)


def total_mass_kg(rows: list[PartsListRow]) -> float:
    """Mass (kg) of the parts with one (the purchased parts' masses are the suppliers')."""
    return sum(m for m in (r.total_mass_kg for r in rows) if m is not None)


def parts_list_csv(rows: list[PartsListRow], design_name: str) -> str:
    """``parts_list.csv``: a ``#`` header line, the column keys, one row per part."""
    buf = io.StringIO()
    buf.write(f"# parts list of design '{csv_comment(design_name)}'; volume of one piece in mm^3 from its mesh, "
              f"masses in kg (density x volume)\n")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow([c[0] for c in COLUMNS])
    for r in rows:
        row = r.as_dict()
        w.writerow([_cell(row[c[0]]) for c in COLUMNS])
    return buf.getvalue()


def read_parts_list_csv(text: str) -> list[dict[str, str]]:
    return list(csv.DictReader(line for line in text.splitlines() if not line.startswith("#")))


def write_parts_list_xlsx(rows: list[PartsListRow], path: Path, design_name: str, version: str = "",
                          date: str = "") -> None:
    """``parts_list.xlsx``: one sheet, title, column titles with units, the column keys,
    one row per part and a total mass row; A4 landscape, one page wide."""
    from openpyxl import Workbook
    from openpyxl.styles import Font, PatternFill

    from prs_geom.exports.sheets import _print_setup

    wb = Workbook()
    ws = wb.active
    ws.title = "parts list"
    xlsx_append(ws, [f"Parts list of design '{design_name}'"])
    ws["A1"].font = Font(bold=True, size=13)
    xlsx_append(ws, [f"{t} ({u})" if u else t for _, t, u in COLUMNS])
    fill = PatternFill("solid", fgColor="DDE6F0")
    for c in range(1, len(COLUMNS) + 1):
        ws.cell(row=2, column=c).font = Font(bold=True)
        ws.cell(row=2, column=c).fill = fill
    xlsx_append(ws, [k for k, _, _ in COLUMNS])
    for c in range(1, len(COLUMNS) + 1):
        ws.cell(row=3, column=c).font = Font(italic=True, color="777777", size=8)
    for r in rows:
        row = r.as_dict()
        xlsx_append(ws, [row[k] for k, _, _ in COLUMNS])     # material names as text, never formulas
        for c, (k, _, _) in enumerate(COLUMNS, start=1):
            if k.endswith("_kg"):
                ws.cell(row=ws.max_row, column=c).number_format = "0.0000"
            elif k == "volume_mm3":
                ws.cell(row=ws.max_row, column=c).number_format = "0.0"
    xlsx_append(ws, ["", "total", sum(r.quantity for r in rows), "", "", "", "", total_mass_kg(rows)])
    ws.cell(row=ws.max_row, column=8).number_format = "0.0000"
    ws.freeze_panes = "A4"                   # title, column titles and keys stay
    for c, w in zip("ABCDEFGHIJ", (6, 16, 9, 18, 10, 14, 12, 12, 22, 70)):
        ws.column_dimensions[c].width = w
    _print_setup(ws, design_name, "parts list", version, date)
    wb.save(path)


def read_parts_list_xlsx(path: Path) -> list[dict[str, Any]]:
    """Rows of the parts list sheet keyed by column key (the total row left out)."""
    from openpyxl import load_workbook

    ws = load_workbook(path, read_only=True).worksheets[0]
    rows = list(ws.iter_rows(values_only=True))
    keys = [c[0] for c in COLUMNS]
    k = next(i for i, r in enumerate(rows) if r and list(r[:len(keys)]) == keys)
    return [dict(zip(keys, r)) for r in rows[k + 1:] if r and isinstance(r[0], int)]
