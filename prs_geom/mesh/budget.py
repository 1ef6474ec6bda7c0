"""Resource guard: refuse a mesh job the machine cannot hold, before it starts.

The triangle count of a thread mesh follows from its tessellation
(:func:`prs_geom.mesh.thread.choose_tessellation`): ``strands x columns per turn x turns x 2``
triangles on the thread surface, plus the end faces. A build meshes the parts three
times: at the design's chord tolerance for the exports, at ``min(tolerance, 2 um)`` for
the interference check (which also holds an FCL BVH and a manifold3d solid of every
distinct mesh; a design of more than :data:`CHECK_WINDOW_TEETH` teeth is checked one
axial window at a time, :func:`check_windows`), and at 0.1 mm for the HTML view. The peak memory is estimated from these
counts with per-triangle costs measured on this code (``benchmarks/bench_build.py`` prints
the measured peak of builds; ``tests/test_safety.py`` checks the estimate against built
meshes); the estimate is meant to be an upper bound within a factor of about two. A build
with worker processes runs the check beside the export meshing: the two peaks add.

The budget defaults to :data:`DEFAULT_BUDGET_FRACTION` of the memory the operating system
reports as available; ``--memory-budget`` on the command line sets it explicitly.
"""
from __future__ import annotations

import math
import os
import re
from dataclasses import dataclass

from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError, ResourceLimitError, format_bytes, format_value

__all__ = [
    "BASE_BYTES", "BYTES_PER_CHECK_TRIANGLE", "BYTES_PER_EXPORT_TRIANGLE", "BYTES_PER_PLACED_TRIANGLE",
    "CHECK_TOLERANCE_MM", "CHECK_WINDOW_TEETH", "DATUM_SLOT_TRIANGLES", "DEFAULT_BUDGET_FRACTION", "Estimate",
    "COARSE_TOLERANCE_MM", "COARSE_WORK_MARGIN", "FINE_TOLERANCE_MM", "MEMORY_BUDGET_ENV", "RUN_OUT_TRIANGLES", "WORKER_BASE_BYTES",
    "WORK_MARGIN", "work_margin", "available_memory_bytes", "check_span",
    "check_windows",
    "default_budget_bytes", "estimate", "guard", "parse_size", "part_triangles",
]

#: Share of the available memory a build may plan to use by default.
DEFAULT_BUDGET_FRACTION = 0.6
#: Bytes per triangle at the peak of each kind of mesh work (measured, rounded up):
#: the interference check (float64 mesh, FCL BVH, manifold3d solid, trimesh caches) and
#: the export meshes (float64 part meshes, the float32 assembly and the writers' buffers).
BYTES_PER_CHECK_TRIANGLE = 1200
BYTES_PER_EXPORT_TRIANGLE = 400
BYTES_PER_PLACED_TRIANGLE = 120
#: Interpreter, libraries and the analysis stages of the main process (bytes), with the
#: resource trackers the pool starts. Calibrated by benchmarks/bench_memory.py.
BASE_BYTES = 320 * 2 ** 20
#: The same for each worker process (bytes): it imports the meshing and checking libraries
#: but runs no analysis stage. Calibrated by benchmarks/bench_memory.py.
WORKER_BASE_BYTES = 220 * 2 ** 20
#: Factor on the mesh work of the estimate at fine chord tolerances (at and below
#: :data:`FINE_TOLERANCE_MM`): the peaks measured there reached up to 1.36 x the
#: per-triangle figures above (the allocator keeps freed blocks); 1.5 keeps the runtime guard
#: (prs_geom.runtime.memwatch) from stopping a build the estimate accepted.
WORK_MARGIN = 1.5
#: At and above :data:`COARSE_TOLERANCE_MM` (the default tolerance) the per-triangle figures
#: hold with :data:`COARSE_WORK_MARGIN` (benchmarks/bench_memory.py: the default build peaks
#: 3 to 6 % under the figures themselves, from run to run up to 4 % apart); between the two
#: tolerances the factor goes linearly in log(tolerance) (measured: 0.002 mm needs 1.1).
COARSE_TOLERANCE_MM = 0.01
FINE_TOLERANCE_MM = 1e-4
COARSE_WORK_MARGIN = 1.03
#: The interference check meshes at no coarser than this (mm), so that the overlap allowed for
#: chordal error (2 x tolerance) stays far below the interference it must detect.
CHECK_TOLERANCE_MM = 0.002
#: Designs with more engaged teeth than this are checked in axial windows of at most this many
#: teeth (:func:`check_windows`): the check meshes at 2 um hold about 12 MB per tooth with
#: their BVHs and solids, so a whole check of 200 teeth would need 2.6 GB.
CHECK_WINDOW_TEETH = 20


def check_windows(design: PRSDesign) -> list[tuple[float, float]] | None:
    """The axial slabs (screw frame, mm) a long design's interference check runs in, or None
    for a design of at most :data:`CHECK_WINDOW_TEETH` engaged teeth (checked whole).

    The engaged length is cut into ceil(n / CHECK_WINDOW_TEETH) windows of whole teeth, as
    equal as whole teeth allow; the first and last slab run on to the screw's ends and
    hold the end gears. The cuts lie at tooth boundaries inside the thread, away from every
    part's end face (:func:`prs_geom.checks.interference.windowed_interference_checks`
    trims the overlap solids at them and drops the faces the cuts make).
    """
    n = design.thread.engaged_teeth
    if n <= CHECK_WINDOW_TEETH:
        return None
    k = math.ceil(n / CHECK_WINDOW_TEETH)
    p = design.thread.pitch_mm
    cuts = [round(i * n / k) * p for i in range(1, k)]
    return list(zip([-math.inf, *cuts], [*cuts, math.inf]))


def check_span(design: PRSDesign) -> tuple[float, float] | None:
    """The axial span (screw frame, mm) the interference check meshes for an actuator: the
    nut assembly at mid-stroke widened by one pitch at each end; None without an actuator.

    Every part but the screw lies inside it, and the thread engagement is the same all along
    the stroke, so the screw beyond it meets nothing the check looks for; the stroke ends
    are checked analytically (:func:`prs_geom.geometry.actuator.stroke_end_checks`)."""
    from prs_geom.geometry.actuator import actuator_layout

    lay = actuator_layout(design)
    if lay is None:
        return None
    p = design.thread.pitch_mm
    return lay.nut_assembly_z[0] - p, lay.nut_assembly_z[1] + p


def available_memory_bytes() -> int:
    """Memory available to new work (bytes): MemAvailable of /proc/meminfo, else the
    physical memory."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return 8 * 2 ** 30


#: Environment variable that sets the budget when none is passed (CLI and Python API alike).
MEMORY_BUDGET_ENV = "PRS_GEOM_MEMORY_BUDGET"


def default_budget_bytes() -> int:
    """$PRS_GEOM_MEMORY_BUDGET (a size such as ``8G``), else
    :data:`DEFAULT_BUDGET_FRACTION` of the available memory."""
    env = os.environ.get(MEMORY_BUDGET_ENV)
    if env:
        return parse_size(env, MEMORY_BUDGET_ENV)
    return int(DEFAULT_BUDGET_FRACTION * available_memory_bytes())


_SIZE_RE = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][+-]?[0-9]+)?)\s*([kKmMgGtT])[iI]?[bB]?\s*$")


def parse_size(text: str, flag: str = "--memory-budget") -> int:
    """Bytes of a size with its unit, ``"8G"``, ``"512M"``, ``"2.5GB"``, ``"64KiB"`` (binary:
    K = 1024 bytes). A bare number is refused: ``--memory-budget 100`` once meant 100 bytes
    where the user meant megabytes."""
    m = _SIZE_RE.match(str(text)[:64])
    if not m:
        shown = str(text)[:40] + ("..." if len(str(text)) > 40 else "")
        raise DesignError(flag, shown, "must be a size with a unit, K, M or G (binary: 1K = 1024 bytes), "
                                       "such as 512M, 8G or 2.5G")
    value = float(m[1]) * 1024 ** " KMGT".index(m[2].upper())
    if not math.isfinite(value) or value <= 0:
        raise DesignError(flag, text, "must be a positive size")
    return int(value)


def _millions(n: float) -> str:
    v = n / 1e6
    return f"{v:.2f} M" if v < 1e5 else f"{v:.3g} M"


def _half_step(sagitta_ratio: float) -> float:
    """Half the polygon step angle (rad) whose sagitta is ``sagitta_ratio`` x the radius:
    acos(1 - x), by its series where x is below float resolution."""
    return math.acos(1.0 - sagitta_ratio) if sagitta_ratio > 1e-8 else math.sqrt(2.0 * sagitta_ratio)


#: Triangles the datum slot adds to an external / internal part (its five faces and face A
#: re-triangulated around it; measured 24 to 82 on the default and test designs).
DATUM_SLOT_TRIANGLES = {False: 40.0, True: 80.0}


#: Triangles the two run-outs of an actuator's part add, per column of a turn (the tools
#: have as many segments, :func:`prs_geom.mesh.thread.apply_run_outs`): measured on the
#: default, a tiny and an 8-tooth design at 0.01 and 0.002 mm, the wheel exits 1.2 to 21 a
#: column on the screw, the chamfers 1.1 to 2.4 on the roller and 6.9 to 7.7 on the nut.
RUN_OUT_TRIANGLES = {"screw": 21.0, "roller": 2.0, "nut": 7.0}


def part_triangles(design: PRSDesign, tol: float, screw_length: float | None = None) -> dict[str, float]:
    """Estimated triangles of the screw, roller and nut meshes at chord tolerance ``tol`` (mm),
    as floats (a length of 1e300 mm gives an estimate, not an overflow); ``screw_length``:
    the screw meshed over this length (mm) only, as the interference check does."""
    from prs_geom.geometry.frames import screw_thread_length, thread_length
    from prs_geom.mesh.thread import choose_tessellation, part_chord_tolerance
    from prs_geom.geometry.profiles import ThreadProfiles

    prof = ThreadProfiles.from_design(design)
    lengths = {"screw": screw_thread_length(design) if screw_length is None else screw_length,
               "roller": thread_length(design), "nut": thread_length(design)}
    out = {}
    for name in ("screw", "roller", "nut"):
        p = getattr(prof, name)
        part_tol = part_chord_tolerance(p, tol)
        tess = choose_tessellation(p, part_tol)
        strands = p.starts * (2 * len(tess.flank_radii) + 1)
        turns = lengths[name] / p.lead
        surface = 2.0 * strands * tess.columns_per_turn * turns
        ends = 4.0 * tess.columns_per_turn + 2.0 * strands   # two end fans/annuli
        if p.internal:  # body cylinder (two triangles a facet) and its share of the end annuli
            body = 0.5 * design.nut.outer_diameter_mm
            ends += 4.0 * max(12.0, math.pi / _half_step(part_tol / body))
        # the datum slot: its five faces and the re-triangulated face A around it (measured
        # 36 to 82 triangles on the default and test designs)
        out[name] = surface + ends + DATUM_SLOT_TRIANGLES[p.internal]
        if design.has_actuator:   # the run-outs re-triangulate both ends (RUN_OUT_TRIANGLES)
            out[name] += RUN_OUT_TRIANGLES[name] * tess.columns_per_turn
    return out


@dataclass(frozen=True)
class Estimate:
    """Triangles and peak memory of a job (bytes)."""

    export_triangles: float
    placed_triangles: float
    check_triangles: float
    peak_bytes: float
    parts: dict[str, float]

    def describe(self) -> str:
        return (f"{_millions(self.export_triangles)} triangles in the part meshes, "
                f"{_millions(self.check_triangles)} for the interference check, estimated peak "
                f"memory {format_bytes(self.peak_bytes)}")


def estimate(design: PRSDesign, export: bool = True, check: bool = True, workers: int = 0) -> Estimate:
    """Estimated triangles and peak memory of meshing ``design`` (exports and/or check).

    ``workers``: worker processes of the build (:mod:`prs_geom.runtime.pool`). With workers the
    interference check runs beside the export meshing, so their peaks add, and each worker
    carries its own interpreter and libraries (:data:`BASE_BYTES`)."""
    tol = design.mesh.chord_tolerance_mm
    parts = part_triangles(design, tol)
    export_tri = sum(parts.values())
    placed = parts["screw"] + parts["nut"] + design.roller.count * parts["roller"]
    check_tol = min(tol, CHECK_TOLERANCE_MM)
    span = check_span(design)
    check_tri = sum(part_triangles(design, check_tol, None if span is None else span[1] - span[0]).values()) \
        if check else 0
    if check_windows(design) is not None:
        # one window (plus a pitch of margin at each end) is meshed at a time; the screw
        # is longer than the engaged length, so this share over-counts it
        check_tri *= (CHECK_WINDOW_TEETH + 2) / design.thread.engaged_teeth
    peaks = [0.0]
    if export:
        peaks.append(export_tri * BYTES_PER_EXPORT_TRIANGLE + placed * BYTES_PER_PLACED_TRIANGLE)
    if check:
        peaks.append(check_tri * BYTES_PER_CHECK_TRIANGLE)
    work = work_margin(tol) * (sum(peaks) if workers > 0 else max(peaks))
    return Estimate(export_triangles=export_tri if export else 0.0, placed_triangles=placed if export else 0.0,
                    check_triangles=check_tri, peak_bytes=BASE_BYTES + WORKER_BASE_BYTES * max(workers, 0) + work,
                    parts=parts)


def work_margin(tol: float) -> float:
    """The factor on the per-triangle figures at chord tolerance ``tol`` (mm):
    :data:`COARSE_WORK_MARGIN` at and above :data:`COARSE_TOLERANCE_MM`, :data:`WORK_MARGIN`
    at and below :data:`FINE_TOLERANCE_MM`, linear in log(tol) between."""
    lo, hi = math.log(FINE_TOLERANCE_MM), math.log(COARSE_TOLERANCE_MM)
    x = min(max((math.log(tol) - lo) / (hi - lo), 0.0), 1.0)
    return WORK_MARGIN + (COARSE_WORK_MARGIN - WORK_MARGIN) * x


def guard(design: PRSDesign, budget_bytes: int | None = None, export: bool = True,
          check: bool = True, workers: int = 0) -> Estimate:
    """Raise :class:`ResourceLimitError` when meshing ``design`` would exceed the budget
    (``workers``: see :func:`estimate`).

    The message names the estimate, the budget and the design fields that drive it.
    """
    est = estimate(design, export, check, workers)
    budget = default_budget_bytes() if budget_bytes is None else budget_bytes
    if est.peak_bytes > budget:
        biggest = max(est.parts, key=est.parts.get)
        length_field = (("actuator.stroke_mm", design.actuator.stroke_mm) if design.has_actuator and
                        design.screw.length_mm is None else ("screw.length_mm", design.screw.length_mm)) \
            if biggest == "screw" else \
            ("thread.engaged_teeth", design.thread.engaged_teeth)
        source = ("set by --memory-budget" if budget_bytes is not None else
                  f"set by ${MEMORY_BUDGET_ENV}" if os.environ.get(MEMORY_BUDGET_ENV) else
                  f"{DEFAULT_BUDGET_FRACTION:.0%} of the available memory")
        raise ResourceLimitError(
            f"this design is too large to mesh here: {est.describe()}, over the budget "
            f"{format_bytes(budget)} ({source}). The {biggest} mesh is the largest; it is driven by "
            f"{length_field[0]} = {format_value(length_field[1])}, mesh.chord_tolerance_mm = "
            f"{design.mesh.chord_tolerance_mm:g} (the check meshes at min(tolerance, "
            f"{CHECK_TOLERANCE_MM:g} mm)) and the diameters. Shorten the part, coarsen the tolerance, "
            f"or raise the budget with --memory-budget SIZE (e.g. --memory-budget 16G)")
    return est
