"""Design-space sweeps: every combination of starts, rollers, pitch, teeth (and load) at once.

:func:`sweep` evaluates the Cartesian product of the values given for screw/nut starts,
roller count, pitch, engaged teeth and, optionally, fractions of the design load, each
applied to a base design, and tabulates per point (docs/scaleout.md "Design-space sweeps"):

* whether the point is a valid design (status ``ok``), a valid design with warnings
  (``warnings``: it breaks a standard-sizing relation, a plausible range or lets the rollers
  drift axially, the warnings of ``prs-geom validate``, listed in their own columns), or
  not (``invalid``, with the :class:`~prs_geom.model.errors.DesignError` message the model
  raised; a point outside the model's rules does not stop the sweep); ``failed`` when a
  solver did not converge;
* the worst load-distribution coefficient (both sides) of the constant-pitch design at the
  point's design load;
* the worst coefficient of the equal-load graded design (:func:`~prs_geom.analysis.loads.design_pitches`
  at the design load) at 25, 50, 100 and 150 % of that load;
* the axial stiffness (secant, N/um) of both, and the largest pitch correction (um).

How a point is built from the base design (:func:`point_design`): the swept fields are
replaced (``starts`` sets screw and nut starts alike), the pitch lists and the
``[tolerances]`` section are dropped (every point starts at constant pitch, without an
error model), and every dimension the base design took by default
(truncation diameters, roller arc radius, screw length) is derived again for the point's
pitch and teeth; dimensions the base design states are kept, and may then break a rule.

The points run through :func:`prs_geom.runtime.scaleout.run_chunks` in chunks of a fixed size, so the
table is the same, bit for bit, serially, with joblib or on Dask. Sweep order: the product
in the order starts, rollers, pitch, teeth, loads, each axis in the order given (the last
axis varies fastest).

No file I/O here: :class:`SweepResult` gives the rows, the columns with their units and the
CSV text, :func:`print_table` the fixed-width table; the caller writes files. The command
line ``prs-geom sweep`` (:mod:`prs_geom.cli`) parses the options and calls :func:`sweep`.

The command-line parser reads :data:`SERIAL_BELOW` from this module, so numpy, the analysis
layer and the scale-out backends are imported inside the functions that need them.
"""
from __future__ import annotations

import itertools
import math
import numbers
import sys
import warnings
from dataclasses import dataclass, replace
from typing import Any, Sequence

from prs_geom.model.design import PRSDesign
from prs_geom.model.errors import DesignError, DesignWarning, PRSGeomError
from prs_geom.runtime.progress import ProgressFn

__all__ = ["Column", "SweepPoint", "SweepResult", "sweep", "point_design", "evaluate_point",
           "DEFAULT_FRACTIONS", "CHUNK_POINTS", "SERIAL_BELOW", "STATUSES", "print_table"]

#: Loads (fractions of the point's design load) at which the graded design is evaluated.
DEFAULT_FRACTIONS: tuple[float, ...] = (0.25, 0.5, 1.0, 1.5)
#: Points per chunk. Fixed, never derived from the worker count (determinism); a point costs
#: some 30 ms on the default design, so a chunk is worth sending to a process.
CHUNK_POINTS = 4
#: A sweep of fewer points runs in this process unless workers are asked for: starting worker
#: processes (about a second, each imports numpy, scipy and prs_geom) costs more than it saves.
SERIAL_BELOW = 16
#: Status of a row: valid, valid with warnings (the warnings of ``validate``), invalid, failed.
OK, WARNINGS, INVALID, FAILED = "ok", "warnings", "invalid", "failed"
STATUSES = (OK, WARNINGS, INVALID, FAILED)


@dataclass(frozen=True)
class Column:
    """A column of the sweep table: ``name`` (as in the CSV header and the row dicts),
    ``unit`` (``"-"`` for pure numbers and text) and a one-line ``description``."""

    name: str
    unit: str
    description: str


_POINT_COLUMNS = (
    Column("point", "-", "point number, 1 first, in sweep order"),
    Column("screw_starts", "-", "screw starts n_s"),
    Column("nut_starts", "-", "nut starts n_n"),
    Column("rollers", "-", "roller count z"),
    Column("pitch_mm", "mm", "axial pitch p"),
    Column("engaged_teeth", "-", "engaged teeth n"),
    Column("load_fraction", "-", "design load of the point as a fraction of the base design load"),
    Column("design_load_N", "N", "design load F0 of the point"),
    Column("status", "-", "ok (valid); warnings (valid, with the warnings of the next two columns); invalid (the "
                          "design breaks a rule of the model); failed (a solver did not converge)"),
    Column("reason", "-", "the error message of an invalid or failed point, else empty"),
    Column("sizing_warnings", "-", "standard-sizing relations the point breaks, separated by ' | '"),
    Column("plausibility_warnings", "-", "values outside their plausible range and axial roller drift (the "
                                         "other warnings of prs-geom validate), separated by ' | '"),
    Column("constant_max_ldc", "-", "worst load-distribution coefficient, both sides, constant pitch, at F0"),
)
_TAIL_COLUMNS = (
    Column("constant_stiffness_N_per_um", "N/um", "secant axial stiffness of the constant-pitch design at F0"),
    Column("graded_stiffness_N_per_um", "N/um", "secant axial stiffness of the equal-load graded design at F0"),
    Column("max_pitch_correction_um", "um",
           "largest |p_j - p| of the equal-load roller and nut pitch lists (per pitch, not cumulative)"),
)


def _fraction_name(fraction: float) -> str:
    return f"graded_max_ldc_{fraction * 100:g}pct".replace(".", "p")


def _columns(fractions: Sequence[float]) -> tuple[Column, ...]:
    graded = tuple(Column(_fraction_name(f), "-", f"worst coefficient, both sides, of the equal-load graded "
                                                  f"design at {f * 100:g} % of F0") for f in fractions)
    return _POINT_COLUMNS + graded + _TAIL_COLUMNS


@dataclass(frozen=True)
class SweepPoint:
    """One point of a sweep: the values applied to the base design (``index`` from 0)."""

    index: int
    starts: int | None
    rollers: int
    pitch_mm: float
    teeth: int
    load_fraction: float


@dataclass(frozen=True)
class SweepResult:
    """A finished sweep: one row per point, in sweep order.

    Attributes
    ----------
    design_name : str
        Name of the base design.
    base_load_n : float
        Design load of the base design (N); ``load_fraction`` scales it.
    fractions : tuple of float
        Fractions of each point's design load at which the graded design was evaluated.
    columns : tuple of Column
        The table's columns, in order, with units.
    table : tuple of tuple
        Row values in column order; None where a point has no number (invalid or failed).
    """

    design_name: str
    base_load_n: float
    fractions: tuple[float, ...]
    columns: tuple[Column, ...]
    table: tuple[tuple[Any, ...], ...]

    @property
    def units(self) -> dict[str, str]:
        """Column name -> unit."""
        return {c.name: c.unit for c in self.columns}

    def rows(self) -> list[dict[str, Any]]:
        """The rows as new dicts (column name -> value), in sweep order."""
        names = [c.name for c in self.columns]
        return [dict(zip(names, row)) for row in self.table]

    def count(self, status: str = OK) -> int:
        """Number of rows with this status (``"ok"``, ``"warnings"``, ``"invalid"`` or ``"failed"``)."""
        i = [c.name for c in self.columns].index("status")
        return sum(1 for row in self.table if row[i] == status)

    def counts(self) -> dict[str, int]:
        """Rows per status, every status of :data:`STATUSES` (0 included)."""
        return {s: self.count(s) for s in STATUSES}

    def summary(self) -> str:
        """``"N points, a valid, b valid with warnings, c invalid, d failed"``."""
        c = self.counts()
        return (f"{len(self.table)} points, {c[OK]} valid, {c[WARNINGS]} valid with warnings, {c[INVALID]} invalid, "
                f"{c[FAILED]} failed")

    def to_json(self) -> dict[str, Any]:
        """A JSON-ready dict: design, the row count per status, columns (name, unit,
        description) and rows (null where a point has no number)."""
        return {"design": self.design_name, "base_load_N": self.base_load_n, "fractions": list(self.fractions),
                "counts": self.counts(),
                "columns": [{"name": c.name, "unit": c.unit, "description": c.description} for c in self.columns],
                "rows": self.rows()}

    def csv_text(self) -> str:
        """The table as CSV text: a header of the column names (which carry the units), then one
        line per point; floats at full float64 precision (repr), empty cells where a point
        has no number; text (statuses, reasons, warnings) never begins a spreadsheet formula
        (:func:`prs_geom.exports.textsafe.csv_field`)."""
        import csv
        import io

        from prs_geom.exports.textsafe import csv_field

        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow([c.name for c in self.columns])
        for row in self.table:
            w.writerow(["" if v is None else repr(v) if isinstance(v, float) else csv_field(v) for v in row])
        return buf.getvalue()


# --------------------------------------------------------------------------- one point
def point_design(base: PRSDesign, point: SweepPoint) -> PRSDesign:
    """The design of a sweep point (module doc: how it is built from ``base``).

    Raises
    ------
    DesignError
        The point breaks a rule of the model; the field is named as in a design file
        (``roller.count``, ``thread.pitch_mm``...).
    """
    # Dimensions the base design derived from its pitch and teeth must follow the point's;
    # PRSDesign records which fields it took by default (its own bookkeeping, not a field).
    defaulted = getattr(base, "_defaulted", {})

    def part(section: str, obj: Any, **changes: Any) -> Any:
        for path in defaulted:
            sec, key = path.split(".", 1)
            if sec == section:
                changes.setdefault(key, None)
        try:
            return replace(obj, **changes)
        except DesignError as exc:
            raise exc.prefixed(section) from None

    starts = {} if point.starts is None else {"starts": point.starts}
    # a sweep evaluates no error model, and per-tooth tolerance lists would not fit another
    # tooth count: the points carry no [tolerances] section
    untoleranced = {"tolerances": None} if getattr(base, "tolerances", None) is not None else {}
    return base.with_changes(
        **untoleranced,
        thread=part("thread", base.thread, pitch_mm=point.pitch_mm, engaged_teeth=point.teeth),
        screw=part("screw", base.screw, **starts),
        roller=part("roller", base.roller, count=point.rollers, pitch_list_mm=None),
        nut=part("nut", base.nut, pitch_list_mm=None, **starts),
        loading=part("loading", base.loading, axial_load_n=base.loading.axial_load_n * point.load_fraction),
    )


def evaluate_point(design: PRSDesign, fractions: Sequence[float] = DEFAULT_FRACTIONS) -> dict[str, float]:
    """The numbers of one valid point: exactly the calls a designer would make by hand.

    Returns
    -------
    dict
        ``constant_max_ldc``, one ``graded_max_ldc_<pct>pct`` per fraction, the secant
        stiffnesses ``constant_stiffness_N_per_um`` and ``graded_stiffness_N_per_um``
        (N/um) and ``max_pitch_correction_um`` (um).
    """
    from prs_geom.analysis.loads import (axial_stiffness, build_model, design_pitches, forward, off_design,
                                         with_pitch_lists)

    model = build_model(design)
    const = forward(design, model=model)
    pd = design_pitches(design, model=model)
    graded = with_pitch_lists(design, pd)
    off = off_design(graded, fractions, model=model)
    p = design.thread.pitch_mm
    corr = max(abs(x - p) for x in pd.roller_mm + pd.nut_mm)
    out = {"constant_max_ldc": float(max(const.ldc_nr.max(), const.ldc_rs.max()))}
    out.update({_fraction_name(row["load_fraction"]): row["max_ldc"] for row in off})
    out["constant_stiffness_N_per_um"] = axial_stiffness(design, model)["secant_N_per_um"]
    out["graded_stiffness_N_per_um"] = axial_stiffness(graded, model)["secant_N_per_um"]
    out["max_pitch_correction_um"] = corr * 1e3
    return out


def _row(base: PRSDesign, point: SweepPoint, fractions: tuple[float, ...]) -> tuple[Any, ...]:
    """One table row; a rule the point breaks or a solver failure is recorded, not raised."""
    columns = _columns(fractions)
    values: dict[str, Any] = {c.name: None for c in columns}
    values.update(point=point.index + 1, rollers=point.rollers, pitch_mm=point.pitch_mm,
                  engaged_teeth=point.teeth, load_fraction=point.load_fraction,
                  screw_starts=base.screw.starts if point.starts is None else point.starts,
                  nut_starts=base.nut.starts if point.starts is None else point.starts,
                  design_load_N=base.loading.axial_load_n * point.load_fraction, reason="", sizing_warnings="",
                  plausibility_warnings="")
    try:
        from prs_geom.model.plausibility import design_warnings

        design = point_design(base, point)
        sizing, other = design.sizing_warnings(), design_warnings(design)
        values["sizing_warnings"] = " | ".join(sizing)
        values["plausibility_warnings"] = " | ".join(other)
        with warnings.catch_warnings():
            # the sizing relations are in their own column already
            warnings.simplefilter("ignore", DesignWarning)
            values.update(evaluate_point(design, fractions))
        values["status"] = WARNINGS if sizing or other else OK
    except DesignError as exc:
        values["status"], values["reason"] = INVALID, str(exc)
    except PRSGeomError as exc:   # a solver that did not converge: that point only
        values["status"], values["reason"] = FAILED, f"{type(exc).__name__}: {exc}"
    return tuple(values[c.name] for c in columns)


def _evaluate_chunk(payload: tuple[PRSDesign, tuple[SweepPoint, ...], tuple[float, ...]]) -> list[tuple[Any, ...]]:
    """The rows of one chunk of points (the task :func:`run_chunks` sends to the workers)."""
    base, points, fractions = payload
    return [_row(base, p, fractions) for p in points]


# --------------------------------------------------------------------------- the sweep
def _axis(name: str, values: Sequence[Any] | None, default: Any) -> tuple[Any, ...]:
    if values is None:
        return (default,)
    if isinstance(values, (str, bytes)) or not hasattr(values, "__iter__"):
        raise DesignError(name, values, "must be a list of values")
    out = tuple(values)
    if not out:
        raise DesignError(name, [], "must list at least one value")
    return out


def _load_fractions(loads: tuple[Any, ...], fractions: tuple[Any, ...]) -> tuple[tuple[float, ...], tuple[float, ...]]:
    """The load axis and the evaluation fractions as floats, each a number > 0; the
    fractions distinct (they name the table's columns)."""
    for name, axis in (("loads", loads), ("fractions", fractions)):
        for i, f in enumerate(axis):
            if isinstance(f, bool) or not isinstance(f, numbers.Real) or not math.isfinite(f) or f <= 0:
                raise DesignError(f"{name}[{i}]", f, "must be a number > 0 (a fraction of the design load)")
    fractions = tuple(float(f) for f in fractions)
    if len({_fraction_name(f) for f in fractions}) != len(fractions):
        raise DesignError("fractions", list(fractions), "must not repeat a value")
    return tuple(float(f) for f in loads), fractions


def sweep(design: PRSDesign, *, starts: Sequence[int] | None = None, rollers: Sequence[int] | None = None,
          pitch_mm: Sequence[float] | None = None, teeth: Sequence[int] | None = None,
          loads: Sequence[float] | None = None, fractions: Sequence[float] = DEFAULT_FRACTIONS,
          workers: int | None = None, scheduler: Any = None, dask_workers: int | None = None,
          progress: ProgressFn | None = None) -> SweepResult:
    """Evaluate every combination of the given values on ``design`` (module doc).


    Parameters
    ----------
    design : PRSDesign
        The base design; an axis left None keeps its value.
    starts : sequence of int, optional
        Starts of screw and nut alike.
    rollers : sequence of int, optional
        Roller counts z.
    pitch_mm : sequence of float, optional
        Axial pitches p (mm).
    teeth : sequence of int, optional
        Engaged teeth n.
    loads : sequence of float, optional
        Design loads as fractions of the base design load (> 0; 1 when omitted).
    fractions : sequence of float
        Fractions of each point's design load at which the graded design is evaluated
        (default 25, 50, 100, 150 %).
    workers : int, optional
        joblib worker processes (:func:`prs_geom.runtime.scaleout.run_chunks`); default one per CPU,
        but serial for fewer than :data:`SERIAL_BELOW` points. The table does not depend on
        where the points run.
    scheduler : str or distributed.Client, optional
        Run on Dask: ``"local"`` or a scheduler address ``"tcp://host:port"``.
    dask_workers : int, optional
        Run on a local Dask cluster of this many processes.
    progress : callable, optional
        ``progress("sweep", points done, points)``.

    Returns
    -------
    SweepResult

    Raises
    ------
    DesignError
        An empty axis, a load fraction or evaluation fraction that is not a number > 0, or
        invalid backend options. A point the model rejects is a row, not an error.
    EnvironmentFailure
        Dask asked for but not installed, or its scheduler cannot be reached.

    Examples
    --------
    >>> import prs_geom as pg
    >>> result = pg.design_sweep(pg.default_design(), rollers=[8, 10])
    >>> [(row["rollers"], round(row["constant_max_ldc"], 3), round(row["graded_max_ldc_100pct"], 3))
    ...  for row in result.rows()]
    [(8, 1.375, 1.0), (10, 1.429, 1.0)]
    """
    from prs_geom.runtime.scaleout import plan_chunks, run_chunks

    s_axis = _axis("starts", starts, None)
    z_axis = _axis("rollers", rollers, design.roller.count)
    p_axis = _axis("pitch_mm", pitch_mm, design.thread.pitch_mm)
    n_axis = _axis("teeth", teeth, design.thread.engaged_teeth)
    f_axis = _axis("loads", loads, 1.0)
    f_axis, fractions = _load_fractions(f_axis, tuple(fractions))
    points = [SweepPoint(i, s, z, p, n, f)
              for i, (s, z, p, n, f) in enumerate(itertools.product(s_axis, z_axis, p_axis, n_axis, f_axis))]
    if workers is None and scheduler is None and dask_workers is None and len(points) < SERIAL_BELOW:
        workers = 1
    chunks = plan_chunks(len(points), CHUNK_POINTS)
    payloads = [(design, tuple(points[k] for k in c), fractions) for c in chunks]
    parts = run_chunks(_evaluate_chunk, payloads, workers=workers, scheduler=scheduler, dask_workers=dask_workers,
                       progress=progress, stage="sweep", sizes=[len(c) for c in chunks])
    return SweepResult(design.name, design.loading.axial_load_n, fractions, _columns(fractions),
                       tuple(row for part in parts for row in part))


# --------------------------------------------------------------------------- the table as text
def _cell(value: Any, fmt: str) -> str:
    return "-" if value is None else format(value, fmt)


def print_table(result: SweepResult, file: Any = None) -> None:
    """The sweep as a fixed-width table: invalid and failed points with their reason; the
    warnings of a valid point (standard sizing, plausible ranges, roller drift) counted in
    column ``w`` and listed below with the points that draw them."""
    file = file or sys.stdout
    rows = result.rows()
    print(f"design {result.design_name}: {result.summary()}. Worst LDC of both "
          f"sides at constant pitch (const.) and of the equal-load graded design (gr.) at % of the point's "
          f"design load = load x {result.base_load_n:g} N", file=file)
    pcts = [f"{f * 100:g}%" for f in result.fractions]
    print(f"{'pt':>4} {'starts':>6} {'rollers':>7} {'p mm':>6} {'teeth':>5} {'load':>5} {'w':>2} {'const.':>7} "
          + " ".join(f"{'gr.' + p:>8}" for p in pcts) + f" {'k N/um':>8} {'gr. k':>8} {'corr um':>8}", file=file)
    broken: dict[tuple[str, str], list[int]] = {}
    for row in rows:
        starts = str(row["screw_starts"]) if row["screw_starts"] == row["nut_starts"] else \
            f"{row['screw_starts']}/{row['nut_starts']}"
        sizing = []
        for kind, col in (("sizing", "sizing_warnings"), ("plausibility", "plausibility_warnings")):
            for msg in (row[col].split(" | ") if row[col] else []):
                sizing.append(msg)
                broken.setdefault((kind, msg), []).append(row["point"])
        line = (f"{row['point']:>4} {starts:>6} {row['rollers']!s:>7} {row['pitch_mm']!s:>6} "
                f"{row['engaged_teeth']!s:>5} {row['load_fraction']:>5g}")
        if row["status"] not in (OK, WARNINGS):
            print(f"{line} {'':>2} {row['status']}: {row['reason']}", file=file)
            continue
        graded = " ".join(f"{row[_fraction_name(f)]:8.4f}" for f in result.fractions)
        print(f"{line} {len(sizing) or '':>2} {_cell(row['constant_max_ldc'], '7.4f')} {graded} "
              f"{_cell(row['constant_stiffness_N_per_um'], '8.1f')} {_cell(row['graded_stiffness_N_per_um'], '8.1f')} "
              f"{_cell(row['max_pitch_correction_um'], '8.3f')}", file=file)
    for (kind, msg), pts in broken.items():
        print(f"{kind} (warning, points {_ranges(pts)}): {msg}", file=file)


def _ranges(numbers_: list[int]) -> str:
    """``1-4, 7, 9-10`` of ascending point numbers."""
    out: list[str] = []
    start = prev = numbers_[0]
    for k in numbers_[1:] + [None]:
        if k is not None and k == prev + 1:
            prev = k
            continue
        out.append(str(start) if start == prev else f"{start}-{prev}")
        if k is not None:
            start = prev = k
    return ", ".join(out)
