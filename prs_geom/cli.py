"""Command-line interface ``prs-geom``.

Exit codes (docs/cli.md "Exit codes"):

* 0 success;
* 1 the analysis found a problem (e.g. interference) or a solver did not converge;
* 2 bad input: a design value (the message names the field, the value and the rule), a
  command-line flag, or an output path that holds files prs-geom did not write (or files it
  wrote that were edited since); nothing is written;
* 3 the environment cannot do it: a path that cannot be read or written (permission,
  disk full, missing folder; the message names the path and the OS reason), a missing
  optional extra (the message gives the install command) or a job larger than the memory
  budget; checked before any work, nothing is written;
* 70 an internal error (a bug: please report it with the ``--debug`` traceback);
* 130 interrupted by Ctrl-C (SIGINT), 143 terminated (SIGTERM): the temporary output is
  removed and one line ``interrupted`` is printed.

``--debug`` (anywhere on the command line) shows the traceback of any error.
"""
from __future__ import annotations

import argparse
import signal
import sys
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Sequence

from prs_geom._version import __version__
from prs_geom.model.design import PRSDesign, default_design
from prs_geom.exports.output import check_output_dir
from prs_geom.mesh.budget import MEMORY_BUDGET_ENV, parse_size
from prs_geom.model.errors import (DesignError, DesignWarning, EnvironmentFailure, OutputRefused, PRSGeomError,
                                   ResourceLimitError)
from prs_geom.model.io import PRS_KINDS, check_output_file, dumps_toml, load_design, write_file_atomic
from prs_geom.runtime.progress import ConsoleProgress, silent

__all__ = ["EXIT_OK", "EXIT_FOUND", "EXIT_INPUT", "EXIT_ENVIRONMENT", "EXIT_INTERNAL", "EXIT_SIGINT",
           "EXIT_SIGTERM", "FLAG_OF_PARAMETER", "UsageError", "Terminated", "make_parser", "flag_named", "main",
           "entry_point", "cmd_init", "cmd_validate", "cmd_build", "cmd_contact", "cmd_check", "cmd_loads",
           "cmd_rating", "cmd_design_pitch", "cmd_tolerance", "cmd_sweep", "cmd_harmonic"]

EXIT_OK, EXIT_FOUND, EXIT_INPUT, EXIT_ENVIRONMENT = 0, 1, 2, 3
EXIT_INTERNAL, EXIT_SIGINT, EXIT_SIGTERM = 70, 130, 143


class UsageError(PRSGeomError):
    """Bad command-line usage (exit code 2)."""


class Terminated(BaseException):
    """Raised in the main thread by the SIGTERM handler (not an Exception: nothing may
    swallow it on the way out)."""


def _memory_budget(args: argparse.Namespace) -> int | None:
    """The --memory-budget flag in bytes; None lets the guard take its default
    (:func:`prs_geom.mesh.budget.default_budget_bytes`)."""
    text = getattr(args, "memory_budget", None)
    return None if text is None else parse_size(text, "--memory-budget")


class _DesignKinds(Mapping):
    """:data:`prs_geom.pipeline.DESIGN_KINDS` without importing the pipeline (or the harmonic
    drive's model) to read a screw's design: ``build`` starts a rebuild's plot process
    before those imports (:func:`_early_plot_process`)."""

    def __getitem__(self, kind: str) -> type:
        if kind == "harmonic":
            from prs_geom.harmonic.model import HarmonicDesign

            return HarmonicDesign
        return PRS_KINDS[kind]

    def __iter__(self):
        return iter([*PRS_KINDS, "harmonic"])

    def __len__(self) -> int:
        return len(PRS_KINDS) + 1


def _load_any(path: str | None):
    """A PRS or harmonic design (by the file's ``kind``); the default PRS without a file."""
    if path is None:
        return default_design()
    return load_design(path, _DesignKinds())


def _load(path: str | None) -> PRSDesign:
    """A PRS design; a harmonic design file is an input error for the PRS commands."""
    d = _load_any(path)
    if not isinstance(d, PRSDesign):
        raise DesignError("kind", "harmonic", "this command needs a planetary roller screw design "
                                              "(use 'prs-geom harmonic' or 'prs-geom build')")
    return d


def _warn(design) -> None:
    for msg in getattr(design, "sizing_warnings", lambda: [])():
        print(f"warning: {msg}", file=sys.stderr)


# --------------------------------------------------------------------------- shared arguments
def _add_budget_arg(parser: argparse.ArgumentParser) -> None:
    """``--memory-budget SIZE`` of the commands that mesh."""
    parser.add_argument("--memory-budget", metavar="SIZE",
                        help=f"largest estimated peak memory to accept, with a unit K, M or G, e.g. 8G or "
                             f"512M (default: ${MEMORY_BUDGET_ENV}, else 60%% of the available memory)")


def _add_design_arg(parser: argparse.ArgumentParser) -> None:
    """The optional DESIGN file argument (the built-in default design without it)."""
    parser.add_argument("design", nargs="?", metavar="DESIGN",
                        help="design file (.toml or .json); the built-in default design if omitted")


def _add_compliance_arg(parser: argparse.ArgumentParser) -> None:
    """``--compliance analytic|fe`` of the commands that solve the load distribution."""
    parser.add_argument("--compliance", choices=("analytic", "fe"),
                        help="tooth compliance of the load model (default: the design's loads.compliance): "
                             "'analytic' (Yamamoto) or 'fe' (finite-element influence matrices, computed once "
                             "and cached; needs pip install \"prs-geom[fe]\"; docs/theory/fe.md)")


def _add_error_args(parser: argparse.ArgumentParser) -> None:
    """The error-model flags of the Monte Carlo commands (on top of the design's ``[tolerances]``)."""
    group = parser.add_argument_group("error model (default: the design's [tolerances] section, else no error)")
    group.add_argument("--flank-um", type=float, metavar="T", help="every loaded flank's axial position, +-T um")
    group.add_argument("--roller-diameter-um", type=float, metavar="T", help="roller pitch diameter, +-T um")
    group.add_argument("--eccentricity-um", type=float, metavar="T",
                       help="screw and nut thread axis offset (half the run-out), T um")
    group.add_argument("--lead-um", type=float, metavar="T", help="base-lead error over the engaged length, +-T um")
    group.add_argument("--temperature-k", type=float, metavar="T", help="temperature difference of each part, +-T K")
    group.add_argument("--distribution", choices=("uniform", "normal"),
                       help="uniform within +-T (default) or normal with T = 3 sigma")
    group.add_argument("--samples", type=int, metavar="N",
                       help="Monte Carlo samples (default: the design's [tolerances], else 1000; "
                            "200 for design-pitch --robust)")
    group.add_argument("--seed", type=int, metavar="S", help="random seed (default 0)")


def _add_execution_args(parser: argparse.ArgumentParser, workers_default: str = "one per CPU") -> None:
    """The execution flags of every command that runs chunked work (validated by
    :func:`_execution`); ``workers_default`` says what no ``--workers`` means."""
    group = parser.add_argument_group("where the work runs (same seed, same numbers on any of them)")
    group.add_argument("--workers", type=int, metavar="N",
                       help=f"local worker processes (joblib; default {workers_default}, 1 = no extra process)")
    group.add_argument("--scheduler", metavar="URL", help="an existing Dask scheduler, e.g. tcp://host:8786, "
                       "or 'local' (needs pip install \"prs-geom[dask]\")")
    group.add_argument("--dask-workers", type=int, metavar="N", help="start a local Dask cluster of N processes")


# --------------------------------------------------------------------------- commands
def _write_out_file(path: str, text: str, force: bool) -> None:
    """Write a single output file: refused if it exists (unless ``force``), atomic."""
    target = check_output_file(path, force)
    write_file_atomic(target, text)


def _add_init_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom init`` and its options."""
    p = sub.add_parser("init", help="write the default design as a commented TOML file",
                       description="Write the built-in default design as a commented TOML "
                                   "design file (to stdout, or to --out).")
    p.add_argument("--out", metavar="FILE", help="file to write instead of stdout (an existing file "
                                                 "is refused unless --force)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.set_defaults(func=cmd_init)


def cmd_init(args: argparse.Namespace) -> int:
    """Write the default design as commented TOML to stdout or ``--out``; exit 0."""
    text = dumps_toml(default_design(), header=(
        "prs_geom design file (TOML). Units: mm, N, MPa; angles in degrees.\n"
        "Every key is optional; omitted keys take the built-in default.\n"
        "Teeth are numbered 1..n from the loaded end."))
    if args.out:
        _write_out_file(args.out, text, args.force)
        print(f"wrote {args.out}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _add_validate_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom validate`` and its options."""
    p = sub.add_parser("validate", help="check a design file and estimate the size of its build",
                       description="Read and validate a design file (exit 2 with the field, value and "
                                   "rule when it is invalid), print the sizing warnings and the "
                                   "estimated mesh size and memory of a build. Writes nothing.")
    _add_design_arg(p)
    p.add_argument("--memory-budget", metavar="SIZE",
                   help=f"check the estimate against this budget as build does, e.g. 8G or 512M "
                        f"(default: ${MEMORY_BUDGET_ENV}, else 60%% of the available memory)")
    p.set_defaults(func=cmd_validate)


def cmd_validate(args: argparse.Namespace) -> int:
    """Validate a design (exit 2 naming the field), print its warnings and the build estimate; exit 0."""
    design = _load_any(args.design)
    _warn(design)
    if isinstance(design, PRSDesign):
        from prs_geom.model.plausibility import design_warnings

        # plausible ranges (probably a unit slip) and roller drift: warnings, exit 0
        for msg in design_warnings(design):
            print(f"warning: {msg}", file=sys.stderr)
        from prs_geom.geometry.mechanism import check_layout, layout_warnings

        # every rule of build that needs no meshing (exit 2 naming the field): the gear sizing,
        # the mechanism layout with its standard tables (ISO 286, DIN 472), fits and stack-up;
        # a failed fit or stack-up is a warning, as in build
        for msg in layout_warnings(check_layout(design)):
            print(f"warning: {msg}", file=sys.stderr)
        from prs_geom.geometry.actuator import actuator_layout
        from prs_geom.pipeline import plan_build

        actuator_layout(design)   # the screw ends, bearings and nut mounting, with their tables

        # the same estimate and worker plan as build (exit 2 when build would refuse it)
        workers, est = plan_build(design, _memory_budget(args))
        where = f"with {workers} worker processes" if workers else "in one process"
        print(f"design {design.name} is valid; a build ({where}) meshes {est.describe()}")
    else:
        print(f"design {design.name} (harmonic) is valid")
    return EXIT_OK


def _inside(design_file: str | None, out: Path) -> list[str]:
    """The design file as a path inside the output folder ``out`` (POSIX, relative), if it
    lies there: a build keeps it byte for byte."""
    if design_file is None:
        return []
    src, folder = Path(design_file).resolve(), out.resolve()
    return [src.relative_to(folder).as_posix()] if folder in src.parents else []


def _add_build_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom build`` and its options."""
    p = sub.add_parser("build", help="run every stage and write all exports and report.json",
                       description="Run every stage on a design and write all exports plus "
                                   "report.json into an output folder, atomically: a failed "
                                   "run leaves an earlier output untouched.")
    _add_design_arg(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default exports/<design name>): a new "
                                                "path, an empty folder or an earlier prs-geom output "
                                                "folder; anything else is refused")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.add_argument("--screw", action="append", choices=["theoretical", "nominal"], metavar="KIND",
                   help="screw meshes to export: screw.stl is always the theoretical screw (the state "
                        "the analysis certifies); 'nominal' also writes screw_nominal.stl")
    p.add_argument("--step", action="store_true",
                   help="also write screw.step, roller.step, nut.step: B-rep solids (STEP AP214; needs "
                        "pip install \"prs-geom[step]\"; several seconds)")
    p.add_argument("--only", metavar="GROUPS",
                   help="write only these outputs and report.json, running only the stages they need: a "
                        "comma list of design, meshes, step, sheets, drawings, plots, parts_list, html "
                        "(e.g. --only meshes,sheets); the folder is still replaced whole")
    p.add_argument("--force", action="store_true",
                   help="replace files of an earlier output that were edited since prs-geom wrote them "
                        "(refused otherwise)")
    p.add_argument("--no-cache", action="store_true",
                   help="compute every stage (and the FE influence matrices) afresh instead of reusing the "
                        "cached results of stages whose inputs did not change; the outputs are the same "
                        "(docs/cache.md)")
    _add_compliance_arg(p)
    _add_budget_arg(p)
    p.set_defaults(func=cmd_build)


def cmd_build(args: argparse.Namespace) -> int:
    """Run every stage and write all exports and report.json into the output folder (its path on stdout)."""
    design = _load_any(args.design)
    _warn(design)
    if args.compliance is not None and not isinstance(design, PRSDesign):
        raise UsageError("--compliance applies to planetary roller screw designs, not to a harmonic drive")
    if isinstance(design, PRSDesign):
        design = _with_compliance(design, args)
    out = Path(args.out) if args.out else Path("exports") / design.name
    plot_process = _early_plot_process(design, out, args)
    try:
        from prs_geom.exports.output import legacy_manifest

        # every precondition before any work: the output folder (edited files need --force; the
        # design file may lie inside it) here, the optional extra and the memory in build()
        check_output_dir(out, force=args.force, keep=_inside(args.design, out))
        if legacy_manifest(out):
            print(f"warning: {out} was written by an older prs-geom (its manifest records names, not "
                  f"contents): it is replaced this once without checking for edited files", file=sys.stderr)
        progress = args.progress
        from prs_geom.pipeline import BuildOptions, build

        only = tuple(g.strip() for g in args.only.split(",")) if args.only is not None else ()
        options = BuildOptions(nominal_screw="nominal" in (args.screw or []), step=args.step, only=only)
    except BaseException:
        if plot_process is not None:
            plot_process.close()
        raise
    report = build(design, out, progress=progress, memory_budget=_memory_budget(args), options=options,
                   force=args.force, source=args.design, cache=False if args.no_cache else None,
                   plot_process=plot_process)
    sizing = design.sizing_warnings() if isinstance(design, PRSDesign) else []
    for msg in report["warnings"][len(sizing):]:   # the sizing warnings were printed above
        print(f"warning: {msg}", file=sys.stderr)
    if not args.quiet:
        print(f"wrote {len(report['files'])} files to {out}", file=sys.stderr)
    print(str(out / "report.json"))
    return EXIT_OK


def _early_plot_process(design, out: Path, args: argparse.Namespace):
    """The rebuild's plot process (:mod:`prs_geom.runtime.sidecar`), started now, before the
    pipeline's imports and the output folder's check, when ``out`` holds a complete build of
    the same design (its manifest's ``design_sha256``): the designer's loop of a changed load,
    whose figures are most of the work left. :func:`prs_geom.pipeline.build` keeps it only
    when the stage cache confirms it; an input error before the build closes it."""
    from prs_geom.exports.output import read_manifest
    from prs_geom.model.io import design_hash
    from prs_geom.runtime.pool import default_workers
    from prs_geom.runtime.stage_cache import enabled

    if not isinstance(design, PRSDesign) or args.no_cache or args.only is not None or default_workers() <= 0 \
            or not enabled():
        return None
    manifest = read_manifest(out) or {}
    if not manifest.get("complete") or manifest.get("design_sha256") != design_hash(design):
        return None
    from prs_geom.exports.plots import warm_up
    from prs_geom.runtime.sidecar import Sidecar

    return Sidecar(warm_up)


def _print_json(obj) -> None:
    import json

    print(json.dumps(obj, indent=2))


def _add_contact_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom contact`` and its options."""
    p = sub.add_parser("contact", help="screw-roller and roller-nut contact points and the "
                                       "theoretical screw pitch diameter",
                       description="Analytic contact points (collinear-normal Newton-Raphson) of "
                                   "screw-roller and roller-nut, and the screw pitch diameter that "
                                   "removes the interference. Angles: see docs/outputs.md 'Contact and interference'.")
    _add_design_arg(p)
    p.add_argument("--json", action="store_true", help="print the report.json 'contact' section")
    p.set_defaults(func=cmd_contact)


def cmd_contact(args: argparse.Namespace) -> int:
    """Print the contact points and the theoretical screw pitch diameter (or the JSON section); exit 0."""
    from prs_geom.analysis.contact import analyse_contact
    from prs_geom.exports.report import contact_section

    design = _load(args.design)
    _warn(design)
    rep = contact_section(analyse_contact(design))
    if args.json:
        _print_json(rep)
        return EXIT_OK
    sr = rep["screw_roller"]
    print(f"design {design.name}: screw-roller and roller-nut contacts (roller 0, middle tooth)")
    print(f"{'contact':<28}{'r_part mm':>12}{'th_part deg':>13}{'r_roller mm':>13}"
          f"{'th_roller deg':>15}{'gap mm':>13}{'iter':>6}")
    rows = [("screw-roller upper, nominal", sr["upper_at_nominal"]),
            ("screw-roller lower, nominal", sr["lower_at_nominal"]),
            ("screw-roller upper, theor.", sr["upper_at_theoretical"]),
            ("roller-nut upper", rep["roller_nut"]["upper"]),
            ("roller-nut lower", rep["roller_nut"]["lower"])]
    for label, c in rows:
        print(f"{label:<28}{c['part_radius_mm']:12.6f}{c['part_angle_deg']:13.5f}"
              f"{c['roller_radius_mm']:13.6f}{c['roller_angle_deg']:15.5f}{c['gap_mm']:13.3e}"
              f"{c['iterations']:6d}")
    print(f"screw pitch diameter: nominal {sr['nominal_pitch_diameter_mm']:.6f} mm, theoretical "
          f"{sr['theoretical_pitch_diameter_mm']:.6f} mm (correction {sr['diameter_correction_mm']:.6f} mm, "
          f"clearance {sr['clearance_mm']} mm)")
    print(f"interference at the nominal diameter: {sr['interference_at_nominal_mm']:.6f} mm axial, "
          f"{sr['interference_at_nominal_normal_mm']:.6f} mm along the normal")
    return EXIT_OK


def _add_check_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom check`` and its options."""
    p = sub.add_parser("check", help="interference check of the assembly (exit 1 when parts interfere)",
                       description="FCL collision of every pair of parts; manifold3d overlap volumes. "
                                   "Exit code 1 when interference is found.")
    _add_design_arg(p)
    p.add_argument("--screw", choices=("corrected", "nominal"), default="corrected",
                   help="screw pitch diameter: the theoretical one (default) or the nominal one")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    _add_budget_arg(p)
    p.set_defaults(func=cmd_check)


def cmd_check(args: argparse.Namespace) -> int:
    """Interference check of the assembly; exit 1 when parts interfere."""
    from prs_geom.checks.interference import interference

    from prs_geom.mesh.budget import guard

    design = _load(args.design)
    _warn(design)
    guard(design, _memory_budget(args), export=False, check=True)
    progress = args.progress
    rep = interference(design, args.screw, progress=progress)
    if args.json:
        _print_json(rep)
    else:
        print(f"interference check, {args.screw} screw (pitch diameter "
              f"{rep['screw_pitch_diameter_mm']:.6f} mm), mesh tolerance {rep['chord_tolerance_mm']} mm, "
              f"{rep['pairs_checked']} part pairs")
        for row in rep["pairs"]:
            print(f"  INTERFERENCE {row['pair'][0]} / {row['pair'][1]}: {row['volume_mm3']:.4f} mm3, "
                  f"mean thickness {row['mean_thickness_mm'] * 1e3:.2f} um, teeth {row['teeth']}")
        for row in rep["contact_within_tolerance"]:
            print(f"  contact within tolerance {row['pair'][0]} / {row['pair'][1]}: mean thickness "
                  f"{row['mean_thickness_mm'] * 1e3:.3f} um")
        print("interference found" if rep["found"] else "no interference")
    return EXIT_FOUND if rep["found"] else EXIT_OK


def _add_loads_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom loads`` and its options."""
    p = sub.add_parser("loads", help="load distribution over the thread teeth",
                       description="Tooth loads (nonlinear Hertz + Yamamoto or finite-element teeth + "
                                   "bodies) of the design's pitch lists, coefficients, stiffness, off-design "
                                   "loads; with --compliance fe also the model risk.")
    _add_design_arg(p)
    p.add_argument("--load", type=float, metavar="N", help="axial load in N instead of the design load")
    p.add_argument("--json", action="store_true", help="print the report.json 'loads' section")
    _add_compliance_arg(p)
    p.set_defaults(func=cmd_loads)


def cmd_loads(args: argparse.Namespace) -> int:
    """Print the tooth-load distribution (or the JSON section), with ``--compliance fe`` the model risk; exit 0."""
    from prs_geom.analysis.loads import load_distribution
    from prs_geom.exports.report import loads_section

    design = _load(args.design)
    _warn(design)
    if args.load is not None and not (args.load > 0):
        raise DesignError("--load", args.load, "must be > 0 N")
    if args.load is not None:
        from dataclasses import replace
        try:
            design = design.with_changes(loading=replace(design.loading, axial_load_n=args.load))
        except DesignError as exc:
            raise exc.renamed("--load") from None
    design = _with_compliance(design, args)
    progress = args.progress

    models = _load_models(design, progress=progress)
    rep = loads_section(load_distribution(design, models.model, progress), models.cache_report)
    risk = models.model_risk(design)
    if args.json:
        if risk is not None:
            from prs_geom.exports.report import model_risk_section

            rep["model_risk"] = model_risk_section(risk)
        _print_json(rep)
        return EXIT_OK
    print(f"design {design.name}: {rep['design_load_N']:.0f} N, {rep['installation']}, "
          f"{design.roller.count} rollers x {design.thread.engaged_teeth} teeth")
    print(f"{'tooth':>5} {'LDC nut-roller':>15} {'LDC roller-screw':>17} {'const. nut-roller':>18} "
          f"{'const. roller-screw':>20}")
    c = rep["constant_pitch"]
    for j in range(len(rep["ldc_nut_roller"])):
        print(f"{j + 1:5d} {rep['ldc_nut_roller'][j]:15.6f} {rep['ldc_roller_screw'][j]:17.6f} "
              f"{c['ldc_nut_roller'][j]:18.6f} {c['ldc_roller_screw'][j]:20.6f}")
    print(f"max LDC {rep['max_ldc']:.4f} (constant pitch {c['max_ldc']:.4f}); axial stiffness "
          f"{rep['axial_stiffness_N_per_um']:.1f} N/um (secant)")
    for row in rep["off_design"]:
        print(f"  at {row['load_fraction'] * 100:5.0f} % load: max LDC {row['max_ldc']:.4f}")
    sens = rep["sensitivity"]
    print(f"a {sens['pitch_error_um']:g} um error on one pitch changes a coefficient by up to "
          f"{max(sens['max_ldc_change_roller'], sens['max_ldc_change_nut']):.4f}")
    if risk is not None:
        _print_model_risk(risk, models)
    return EXIT_OK


def _load_models(design: PRSDesign, contact=None, progress=silent):
    """:func:`prs_geom.pipeline.load_models`, printing the FE cache's integrity warnings."""
    from prs_geom.pipeline import load_models

    models = load_models(design, contact, progress)
    for cache in (models.cache, models.alternative_cache):
        for msg in cache.warnings if cache is not None else ():
            print(f"warning: {msg}", file=sys.stderr)
    return models


def _with_compliance(design: PRSDesign, args: argparse.Namespace) -> PRSDesign:
    """The design with ``--compliance`` applied; the FE extra checked before any work."""
    if getattr(args, "compliance", None) is not None:
        from dataclasses import replace

        design = design.with_changes(loads=replace(design.loads, compliance=args.compliance))
    if design.loads.compliance == "fe":
        from prs_geom.analysis.fe.cache import require_fe

        require_fe()
    return design


def _design_model(design: PRSDesign):
    """The load model of the design's ``loads.compliance`` (FE matrices from the cache)."""
    design = _with_compliance(design, argparse.Namespace())

    return _load_models(design).model


def _print_model_risk(risk, models) -> None:
    """The model-risk table of ``loads --compliance fe``: the worst coefficient per side of
    every set of pitch lists under every model at every load of the study."""
    for cache, what in ((models.cache, "finite-element influence matrices"),
                        (models.alternative_cache, "matrices of the sections cut at the engaged teeth")):
        if cache is not None:
            src = "read from the cache" if all(cache.hits.values()) else "computed and stored in the cache"
            print(f"{what} {src} {cache.folder} ({cache.seconds:.1f} s)")
    print("model risk: the worst coefficient, nut-roller / roller-screw, of each set of pitch lists under the "
          "FE model (fe), each documented alternative and the analytic model:")
    loads = "".join(f"{f'{fr * 100:.0f} % load':>16}" for fr in risk.load_fractions)
    for lists, made in risk.list_sets():
        print(f"  {lists}" + (f" designed with {made}" if made else "") + ":")
        print(f"    {'model':<40}{loads}")
        for name in risk.models:
            cells = "".join(f"{'%.4f / %.4f' % risk.worst(lists, made, name, fr):>16}" for fr in risk.load_fractions)
            print(f"    {name:<40}{cells}")
    print("  models:")
    for k, v in risk.descriptions.items():
        print(f"    {k}: {v}")
    print(f"largest difference of a coefficient between the models: {risk.largest_model_difference:.4f}")
    print("the FE matrices are ring loads: where the rollers carry unequal loads they are an approximation "
          "(docs/theory/fe.md)")


def _add_rating_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom rating`` and its options."""
    p = sub.add_parser("rating", help="load ratings, life, limits, efficiency and stiffness",
                       description="Basic dynamic and static axial load ratings from the contact geometry, the "
                                   "L10 life of a duty (catalogue form and from the actual tooth loads of constant, "
                                   "equal-load and, with a spectrum, robust pitch), critical speed, buckling, nut "
                                   "speed limit, efficiency, torques and axial stiffness with a preloaded double "
                                   "nut (docs/theory/ratings.md). Defaults come from the design's [rating] and "
                                   "[supports] sections.")
    _add_design_arg(p)
    p.add_argument("--spectrum", metavar="FILE", help="duty cycle: [[case]] load_n, time_share, speed_rpm (speeds "
                                                      "required); also designs the robust pitch for it")
    p.add_argument("--mean-load", type=float, metavar="N", help="equivalent load F_m (N) instead of the design load")
    p.add_argument("--speed-rpm", type=float, metavar="R", help="mean screw speed n_m (rpm; default rating.speed_rpm)")
    p.add_argument("--life-hours", type=float, metavar="H", help="target life for the required dynamic load rating (h)")
    p.add_argument("--fw", type=float, metavar="F", help="operating factor f_w, 1 to 5 (default rating.operating_factor)")
    p.add_argument("--reliability", type=float, metavar="PCT", help="reliability of the life, 90 to 99 %% (default 90)")
    p.add_argument("--json", action="store_true", help="print the report.json 'rating' section")
    p.add_argument("--strict", action="store_true",
                   help="exit 1 when a limit check fails (speed, d n, critical speed, buckling, static safety); "
                        "without it a failed check is a warning on stderr and the exit code is 0")
    p.set_defaults(func=cmd_rating)


def cmd_rating(args: argparse.Namespace) -> int:
    """Print the ratings, lives, limit checks, efficiency and stiffness; exit 1 on a failed limit with ``--strict``."""
    from prs_geom.analysis.contact import analyse_contact
    from prs_geom.analysis.rating import analyse_rating, rating_case

    design = _load(args.design)
    _warn(design)
    spectrum = None
    if args.spectrum:
        from prs_geom.model.io import load_spectrum

        spectrum = load_spectrum(args.spectrum)
        if not spectrum.has_speeds:
            raise DesignError(f"spectrum file {args.spectrum!r}: case[0].speed_rpm", None,
                              "the ratings need speed_rpm on every [[case]] (the life is counted in revolutions)")
    case = rating_case(design, spectrum, args.mean_load, args.speed_rpm, args.life_hours, args.fw, args.reliability)
    contact = analyse_contact(design)
    design = _with_compliance(design, args)

    model = _load_models(design, contact).model           # the design's loads.compliance, as in build
    robust, note = None, "needs a load spectrum (--spectrum FILE)"
    if spectrum is not None:
        from prs_geom import studies

        # the robust design over this duty and the design's error model (one sample without one)
        tol = design.tolerances
        samples = 200 if tol is not None and tol.any_error else 1
        res = studies.robust_pitch(design, spectrum, tol, samples=samples, contact=contact, model=model,
                                   execution=studies.Execution(workers=1))
        robust = (res.design.pitch_list("roller"), res.design.pitch_list("nut"))
    rating = analyse_rating(design, contact, model, case, robust_lists=robust, robust_note=note)
    from prs_geom.exports.report import limit_warnings, rating_section

    rep = rating_section(rating)
    failed = limit_warnings(rating.checks)
    if args.json:
        _print_json(rep)
    else:
        _print_rating(design.name, rep)
    for msg in rating.limits.supports.warnings:
        print(f"warning: supports: {msg}", file=sys.stderr)
    # a failed limit is a warning, or with --strict an error (exit 1); stdout stays the report
    for msg in failed:
        print(f"{'error' if args.strict else 'warning'}: {msg}", file=sys.stderr)
    return EXIT_FOUND if failed and args.strict else EXIT_OK


def _table(rows: list[list[str]], min_widths: Sequence[int]) -> list[str]:
    """Lines of a text table: the first column left-aligned, the others right-aligned; each
    column is its minimum width, widened so that at least two spaces always separate it from
    the next (no two columns ever touch, whatever the numbers)."""
    widths = [max(w, max(len(r[i]) for r in rows) + 2) for i, w in enumerate(min_widths)]
    return ["".join(c.ljust(w) if i == 0 else c.rjust(w) for i, (c, w) in enumerate(zip(r, widths))).rstrip()
            for r in rows]


def _print_rating(name: str, rep: dict) -> None:
    """The text output of ``prs-geom rating``: ratings and duty, the lives of the pitch
    variants, the limit checks with PASS/FAIL, efficiency and stiffness."""
    print(f"design {name}: {rep['method']}")
    print(f"C_a {rep['dynamic_load_rating_n']:.0f} N, C_0a {rep['static_load_rating_n']:.0f} N; duty "
          f"({rep['duty_source']}): F_m {rep['equivalent_load_n']:.6g} N at n_m {rep['equivalent_speed_rpm']:.6g} rpm, "
          f"f_w {rep['operating_factor']:g}, reliability {rep['reliability_pct']:g} % (a_1 "
          f"{rep['reliability_factor']:.3g})")
    print(f"catalogue life {rep['l10_revolutions']:.4g} revolutions = {rep['l10_hours']:.5g} h; required C_a for "
          f"{rep['target_life_hours']:g} h: {rep['required_dynamic_load_n']:.0f} N; static safety "
          f"{rep['static_safety']:.3g}")
    rows = [["life from the tooth loads", "L (h)", "x constant", "p_max MPa", "s0"]]
    for k, v in rep["distribution_life"].items():
        rows.append([f"  {k}", f"{v['l10_hours']:.5g}", f"{v['gain_factor_over_constant_pitch']:.4f}",
                     f"{v['max_hertz_pressure_mpa']:.0f}", f"{v['static_safety']:.3g}"])
    print("\n".join(_table(rows, (28, 12, 12, 11, 8))))
    if isinstance(rep["robust"], str):
        print(f"  robust pitch: {rep['robust']}")
    lim, eff, dn = rep["limits"], rep["efficiency"], rep["double_nut"]
    print(f"limits: critical speed {lim['critical_speed_rpm']:.5g} rpm ({lim['critical_speed_ends']}, "
          f"{lim['unsupported_length_mm']:g} mm), d n limit {lim['dn_speed_limit_rpm']:.5g} rpm, permissible "
          f"{lim['permissible_speed_rpm']:.5g} rpm; Euler buckling {lim['buckling_load_n']:.5g} N "
          f"({lim['buckling_ends']}, {lim['buckling_length_mm']:g} mm), permissible "
          f"{lim['permissible_buckling_load_n']:.5g} N; supports from the {lim['supports_source']}")
    titles = {"speed": "speed", "dn": "d n", "critical_speed": "critical speed", "buckling": "buckling",
              "static_safety": "static safety s0"}
    rows = [["limit check", "value", "limit", "unit", "margin", "result"]]
    for c in lim["checks"]:
        rows.append([f"  {titles.get(c['name'], c['name'])} ({'max' if c['kind'] == 'upper' else 'min'})",
                     f"{c['value']:.6g}", f"{c['limit']:.6g}", c["unit"], f"{c['margin']:+.3g}",
                     "PASS" if c["passed"] else "FAIL"])
    print("\n".join(_table(rows, (28, 12, 12, 8, 9, 8))))
    print("  margin = limit / value - 1 (max), value / limit - 1 (min); >= 0 passes")
    print(f"efficiency {eff['forward']:.3f} forward, {eff['back_driving']:.3f} back-driving (mu "
          f"{eff['friction_coefficient']:g}); drive torque {eff['drive_torque_nm']:.4g} N m, holding torque "
          f"{eff['holding_torque_nm']:.4g} N m at {eff['torque_load_n']:g} N")
    st = rep["stiffness"]
    print(f"stiffness {st['secant_n_per_um'][0]:.0f} ... {st['secant_n_per_um'][-1]:.0f} N/um (secant); double nut "
          f"preload {dn['preload_n']:.0f} N, lost at {dn['lift_off_load_n']:.0f} N")


def _read_target(path: str, n: int) -> tuple[list[float], list[float]]:
    """Target coefficients from .json / .toml ({nut_roller: [...], roller_screw: [...]}) or
    .csv (columns tooth, nut_roller, roller_screw)."""
    import csv

    from prs_geom.model.io import parse_document, read_input_text

    # read within bounds (regular files only, size cap) and parsed under the input limits
    # of prs_geom.model.io: errors are exit 2 naming "--target file" and the path
    p = Path(path)
    text = read_input_text(p, "--target file")
    try:
        if p.suffix.lower() == ".csv":
            rows = list(csv.DictReader(text.splitlines()))
            data = {k: [float(r[k]) for r in rows] for k in ("nut_roller", "roller_screw")}
        else:
            data = parse_document(text, path, "--target file", "json" if p.suffix.lower() == ".json" else "toml",
                                  prefix="target")
    except DesignError:
        raise
    except (ValueError, KeyError, TypeError, csv.Error) as exc:
        raise DesignError.about_file(path, f"is not a valid target file: {str(exc)[:100]}", "--target file") from None
    out = []
    for key in ("nut_roller", "roller_screw"):
        v = data.get(key) if isinstance(data, dict) else None
        if not isinstance(v, list) or len(v) != n or not all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in v):
            raise DesignError(f"target.{key}", v, f"must be a list of engaged_teeth = {n} numbers")
        out.append([float(x) for x in v])
    return out[0], out[1]


def _add_design_pitch_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom design-pitch`` and its options."""
    p = sub.add_parser("design-pitch", help="pitch lists for equal (or target) load sharing",
                       description="Roller and nut pitch lists that give equal load sharing (every "
                                   "coefficient 1) or a target distribution at the design load, "
                                   "written into a new design file ready for build.")
    _add_design_arg(p)
    p.add_argument("--target", default="equal", metavar="equal|FILE",
                   help="'equal' (default) or a .json/.toml file {nut_roller: [...], roller_screw: [...]} "
                        "or a .csv with columns tooth,nut_roller,roller_screw (n coefficients each, mean 1)")
    p.add_argument("--out", metavar="NEW.toml", help="design file to write (default: stdout); an "
                                                     "existing file is refused unless --force")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.add_argument("--name", help="name of the new design (default <name>-graded, <name>-robust)")
    p.add_argument("--robust", action="store_true",
                   help="minimise a quantile of the worst LDC over a load spectrum and the error model "
                        "instead of equal sharing at the design load (docs/theory/tolerances.md)")
    p.add_argument("--spectrum", metavar="FILE", help="with --robust: load spectrum ([[case]] load_n, "
                                                      "time_share, speed_rpm); default the design load")
    p.add_argument("--quantile", type=float, metavar="Q", help="with --robust: the quantile minimised (0.95)")
    p.add_argument("--json", action="store_true", help="with --robust: print the comparison as JSON "
                                                       "(the design goes to --out)")
    _add_compliance_arg(p)
    _add_error_args(p)
    _add_execution_args(p)
    p.set_defaults(func=cmd_design_pitch)


def cmd_design_pitch(args: argparse.Namespace) -> int:
    """Write a design with equal-load (or target, or ``--robust``) pitch lists to stdout or ``--out``; exit 0."""
    from prs_geom.analysis.loads import design_pitches, forward, with_pitch_lists

    design = _load(args.design)
    _warn(design)
    if args.robust:
        return _design_pitch_robust(args, design)
    for flag in ("spectrum", "quantile", "flank_um", "roller_diameter_um", "eccentricity_um", "lead_um",
                 "temperature_k", "distribution", "samples", "seed", "workers", "scheduler", "dask_workers"):
        if getattr(args, flag) is not None:
            raise UsageError(f"--{flag.replace('_', '-')} goes with --robust")
    n = design.thread.engaged_teeth
    t_nr = t_rs = None
    if args.target != "equal":
        t_nr, t_rs = _read_target(args.target, n)
    if args.out:
        check_output_file(args.out, args.force)            # refuse before the work
    design = _with_compliance(design, args)

    model = _load_models(design, progress=args.progress).model
    pd = design_pitches(design, t_nr, t_rs, model=model)
    new = with_pitch_lists(design, pd, name=args.name or f"{design.name}-graded")
    check = forward(new, model=model)
    err = max(abs(check.ldc_nr - pd.target_nr).max(), abs(check.ldc_rs - pd.target_rs).max())
    how = ("the finite-element tooth compliance (loads.compliance = \"fe\")" if design.loads.compliance == "fe"
           else f"the analytic tooth compliance (Yamamoto, width '{design.loads.tooth_width}')")
    text = dumps_toml(new, header=(
        f"Graded pitch lists of '{design.name}' for target '{args.target}' at "
        f"{design.loading.axial_load_n:g} N ({design.loading.installation}), designed with {how}, "
        f"written by prs-geom design-pitch.\nForward check: largest coefficient error {err:.2e}."))
    if args.out:
        _write_out_file(args.out, text, args.force)
        print(f"wrote {args.out}: largest coefficient error of the forward check {err:.2e}", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return EXIT_OK


def _execution(args: argparse.Namespace, quiet: bool):
    """Where the chunks of a command's work run (the flags of :func:`_add_execution_args`),
    checked before any work: counts >= 1, joblib and Dask not both (the scale-out's own rule,
    named by its parameters, which :func:`main` prints as the flags), the Dask extra present."""
    from prs_geom.runtime.scaleout import require_dask, resolve_backend
    from prs_geom.studies import Execution

    for parameter in ("workers", "dask_workers"):
        count = getattr(args, parameter)
        if count is not None and count < 1:
            raise DesignError(parameter, count, "must be >= 1")
    backend = resolve_backend(2, workers=args.workers, scheduler=args.scheduler, dask_workers=args.dask_workers)
    if backend.kind == "dask":
        require_dask()   # a missing extra is known before any work (exit 3)
    return Execution(workers=args.workers, scheduler=args.scheduler, dask_workers=args.dask_workers,
                     progress=silent if quiet else args.progress)


def _cli_tolerances(args: argparse.Namespace, design: PRSDesign):
    """The design's [tolerances] (or none) with the flags on top."""
    from dataclasses import replace

    from prs_geom.model.design import Tolerances

    base = design.tolerances or Tolerances()
    changes = {}
    for flag, keys in (("flank_um", ("flank_um",)), ("roller_diameter_um", ("roller_diameter_um",)),
                       ("eccentricity_um", ("screw_eccentricity_um", "nut_eccentricity_um")),
                       ("lead_um", ("lead_um",)), ("temperature_k", ("temperature_k",)),
                       ("samples", ("samples",)), ("seed", ("seed",)), ("distribution", ("distribution",))):
        v = getattr(args, flag, None)
        if v is not None:
            for k in keys:
                changes[k] = v
    if args.flank_um is not None:      # a flag replaces any per-tooth allocation of the file
        changes.update(screw_flank_um=None, roller_screw_flank_um=None, roller_nut_flank_um=None,
                       nut_flank_um=None)
    if getattr(args, "load_fraction", None):
        changes["load_fractions"] = tuple(args.load_fraction)
    if changes and design.tolerances is not None and "source" not in changes:
        changes["source"] = design.tolerances.source + " (changed on the command line)"
    elif changes:
        changes["source"] = "given on the command line"
    return replace(base, **changes)   # a bad value names its field, main() prints the flag


def _add_tolerance_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom tolerance`` and its options."""
    p = sub.add_parser("tolerance", help="load sharing under manufacturing errors; tolerance synthesis",
                       description="Monte Carlo study of the worst load-distribution coefficient and the "
                                   "roller load share under the error model, all rollers side by side "
                                   "(docs/theory/tolerances.md). With --target-ldc: the largest flank "
                                   "tolerance that meets it with probability --confidence.")
    _add_design_arg(p)
    _add_error_args(p)
    p.add_argument("--load-fraction", type=float, nargs="+", action="extend", metavar="F",
                   help="loads as fractions of the design load (default: the design's, else 1)")
    p.add_argument("--spectrum", metavar="FILE", help="loads from a spectrum file ([[case]] load_n, time_share)")
    p.add_argument("--target-ldc", type=float, metavar="L", help="synthesise: worst LDC to hold")
    p.add_argument("--confidence", type=float, metavar="C",
                   help="with --target-ldc: probability of holding it (default 0.95, as a Clopper-Pearson "
                        "bound); without: report the worst LDC not exceeded with probability C")
    p.add_argument("--out", metavar="NEW.toml", help="with --target-ldc: write the design with the "
                                                     "synthesised [tolerances] section")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.add_argument("--json", action="store_true", help="print the result as one JSON object")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    _add_execution_args(p)
    p.set_defaults(func=cmd_tolerance)


def cmd_tolerance(args: argparse.Namespace) -> int:
    """The Monte Carlo study of the design's error model, or with ``--target-ldc`` the
    tolerance synthesis (exit 1 when the target cannot be met)."""
    from prs_geom import studies

    design = _load(args.design)
    _warn(design)
    tols = _cli_tolerances(args, design)
    execution = _execution(args, quiet=args.json or args.quiet)
    loads = _spectrum_loads(args)
    if args.confidence is not None:
        studies.check_probability("confidence", args.confidence)
    if args.target_ldc is not None:
        return _tolerance_synthesis(args, design, tols, loads, execution)
    if args.out:
        raise UsageError("--out writes synthesised tolerances: give --target-ldc")
    _require_cli_error_model(args, design)
    study = studies.tolerance_study(design, tols, execution=execution, loads_n=loads, confidence=args.confidence,
                                    model=_design_model(design))
    from prs_geom.exports.report import tolerance_section

    if args.json:
        _print_json(tolerance_section(study))
    else:
        _print_tolerance_study(design, tols, tolerance_section(study))
    return EXIT_OK


def _spectrum_loads(args: argparse.Namespace) -> tuple[float, ...] | None:
    """The loads (N) of ``--spectrum``, None without one; refused beside ``--load-fraction``."""
    if not args.spectrum:
        return None
    if args.load_fraction:
        raise UsageError("give --spectrum or --load-fraction, not both")
    from prs_geom.model.io import load_spectrum

    return load_spectrum(args.spectrum).loads_n


#: The flags that give a term of the error model (a study needs one of them or [tolerances]).
_ERROR_FLAGS = ("flank_um", "roller_diameter_um", "eccentricity_um", "lead_um", "temperature_k")


def _require_cli_error_model(args: argparse.Namespace, design: PRSDesign) -> None:
    """Refuse a study without an error model: no ``[tolerances]`` and no error flag. The
    library's rule names the design field; the message here adds the flags."""
    from prs_geom import studies

    if any(getattr(args, flag, None) is not None for flag in _ERROR_FLAGS):
        return
    try:
        studies.require_error_model(design)
    except DesignError:
        raise UsageError(
            "no error model: the design has no [tolerances] section and no error flag was given (a study "
            "of zero errors only repeats the loads). Give the design a [tolerances] section (e.g. flank_um "
            "= 0.5; docs/theory/tolerances.md) or the errors on the command line: "
            + ", ".join("--" + flag.replace("_", "-") + " T" for flag in _ERROR_FLAGS)) from None


def _tolerance_synthesis(args: argparse.Namespace, design: PRSDesign, tols, loads, execution) -> int:
    """``tolerance --target-ldc``: synthesise the flank tolerances, print them (or JSON) and
    write the design with them to ``--out``; exit 1 when the target cannot be met."""
    from dataclasses import replace

    from prs_geom import studies

    if args.flank_um is not None:
        raise UsageError("--flank-um and --target-ldc: the synthesis chooses the flank tolerance; "
                         "leave out --flank-um")
    confidence = 0.95 if args.confidence is None else args.confidence
    if args.out:
        check_output_file(args.out, args.force)        # refuse before the work
    design_load = design.loading.axial_load_n
    fractions = tols.load_fractions if loads is None else tuple(load / design_load for load in loads)
    res = studies.synthesise(design, args.target_ldc, confidence, tols, samples=tols.samples,
                             seed=tols.seed, load_fractions=fractions, execution=execution,
                             model=_design_model(design))
    if res.feasible and args.out:
        new = replace(design, tolerances=res.tolerances)
        _write_out_file(args.out, dumps_toml(new, header=(
            f"'{design.name}' with flank tolerances synthesised by prs-geom tolerance:\n"
            f"{res.tolerances.source}")), args.force)
        if not args.json:
            print(f"wrote {args.out}", file=sys.stderr)
    from prs_geom.exports.report import synthesis_section

    if args.json:
        _print_json({"samples": tols.samples, "seed": tols.seed, "synthesis": synthesis_section(res)})
    else:
        _print_synthesis(res)
    return EXIT_OK if res.feasible else EXIT_FOUND


def _print_tolerance_study(design: PRSDesign, tols, section: dict) -> None:
    """The text output of ``prs-geom tolerance``: the error model, the worst coefficient per
    load and over all loads, the quantile at ``--confidence`` and the importance ranking."""
    per = [v for v in tols.flank_tolerances_um(design.thread.engaged_teeth).values()]
    flank = (f"{tols.flank_um:g} um" if all(x == tols.flank_um for v in per for x in v)
             else f"per tooth {min(min(v) for v in per):g}-{max(max(v) for v in per):g} um")
    print(f"design {design.name}: {section['samples']} samples (seed {section['seed']}), {tols.distribution} "
          f"errors: flank {flank}, roller diameter {tols.roller_diameter_um:g} um, eccentricity "
          f"{tols.screw_eccentricity_um:g}/{tols.nut_eccentricity_um:g} um (screw/nut), lead {tols.lead_um:g} um, "
          f"temperature {tols.temperature_k:g} K")
    print(f"{'load':>8} {'no error':>9} {'median':>8} {'p95':>8} {'p99':>8} {'max':>8} {'roller share max p95':>21}")
    for case in section["cases"]:
        w = case["worst_ldc"]
        print(f"{case['load_fraction'] * 100:7.0f}% {case['deterministic']['worst_ldc']:9.4f} {w['median']:8.4f} "
              f"{w['p95']:8.4f} {w['p99']:8.4f} {w['max']:8.4f} {case['roller_load_share_max']['p95']:21.4f}")
    w = section["worst_ldc"]
    print(f"worst LDC over all loads: median {w['median']:.4f}, p95 {w['p95']:.4f}, p99 {w['p99']:.4f}, "
          f"max {w['max']:.4f}")
    if "at_confidence" in section:
        at = section["at_confidence"]
        bound = "n/a (too few samples)" if at["upper_bound_95"] is None else f"{at['upper_bound_95']:.4f}"
        print(f"with probability {at['confidence']:g}: worst LDC <= {at['worst_ldc_quantile']:.4f} "
              f"(95 % upper bound {bound})")
    for row in section["importance"]:
        print(f"  {row['term']:<20} {row['share'] * 100:6.1f} % of the variance")


def _print_synthesis(res) -> None:
    from prs_geom.exports.report import synthesis_section

    r = synthesis_section(res)
    if not res.feasible:
        print(f"target worst LDC {res.target_ldc:g} with probability {res.confidence:g} cannot be met: "
              f"{r['checks']['reason']}")
        return
    print(f"target: worst LDC <= {res.target_ldc:g} with probability >= {res.confidence:g} "
          f"({r['confidence_bound']})")
    print(f"uniform flank tolerance: +-{res.uniform_um:.2f} um")
    for k, v in res.allocation_um.items():
        print(f"  allocated {k:<22} " + " ".join(f"{x:.2f}" for x in v))
    for name in ("uniform", "allocated"):
        c = r["checks"][name]
        v = c["verification"]
        print(f"{name}: {c['fraction']:.3f} of the samples meet the target (bound {c['clopper_pearson_lower']:.3f}); "
              f"independent re-check (seed {r['checks']['verify_seed']}): {v['fraction']:.3f} "
              f"({'meets' if v['meets_confidence'] else 'MISSES'} {res.confidence:g})")


def _design_pitch_robust(args: argparse.Namespace, design: PRSDesign) -> int:
    from prs_geom import studies
    from prs_geom.model.io import load_spectrum
    from prs_geom.model.spectrum import Spectrum

    if args.target != "equal":
        raise UsageError("--robust chooses its own load sharing: leave out --target")
    if args.out:
        check_output_file(args.out, args.force)            # refuse before the work
    spectrum = load_spectrum(args.spectrum) if args.spectrum else Spectrum.single(design.loading.axial_load_n)
    tols = _cli_tolerances(args, design)
    quantile = 0.95 if args.quantile is None else args.quantile
    samples = args.samples if args.samples is not None else 200
    design = _with_compliance(design, args)

    model = _load_models(design, progress=args.progress).model
    res = studies.robust_pitch(design, spectrum, tols, quantile=quantile, samples=samples, seed=tols.seed, model=model,
                               execution=_execution(args, quiet=args.json),
                               name=args.name or f"{design.name}-robust")
    c = res.comparison
    lines = [f"Robust pitch lists of '{design.name}', written by prs-geom design-pitch --robust:",
             f"objective: {c['objective']}",
             f"family member a_nut_roller = {res.a_nr:.6f}, a_roller_screw = {res.a_rs:.6f} "
             f"(1, 1 = equal sharing at {design.loading.axial_load_n:g} N)"]
    for key, label in (("constant_pitch", "constant pitch"), ("equal_at_design_load", "equal at design load"),
                       ("robust", "robust")):
        lines.append(f"  {label:<21} objective {c[key]['objective']:.4f}")
    text = dumps_toml(res.design, header="\n".join(lines))
    if args.out:
        _write_out_file(args.out, text, args.force)
    elif not args.json:
        sys.stdout.write(text)
    if args.json:
        from prs_geom.exports.report import robust_section

        _print_json(robust_section(res))
    else:
        print("\n".join(lines), file=sys.stderr)
    return EXIT_OK


def _add_sweep_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom sweep`` and its options."""
    from prs_geom.sweep import SERIAL_BELOW

    p = sub.add_parser("sweep", help="design-space sweep: every combination of starts, rollers, pitch, teeth",
                       description="Evaluate every combination of the given screw/nut starts, roller counts, "
                                   "pitches, engaged teeth and load fractions on a base design: validity (or "
                                   "the rule a point breaks), worst LDC at constant pitch and of the equal-load "
                                   "graded design at 25/50/100/150 % load, axial stiffness and the largest "
                                   "pitch correction (docs/scaleout.md).")
    _add_design_arg(p)
    p.add_argument("--starts", type=int, nargs="+", action="extend", metavar="N",
                   help="screw and nut starts to sweep (default: the design's)")
    p.add_argument("--rollers", type=int, nargs="+", action="extend", metavar="Z",
                   help="roller counts to sweep (default: the design's)")
    p.add_argument("--pitch", type=float, nargs="+", action="extend", metavar="MM",
                   help="axial pitches in mm to sweep (default: the design's)")
    p.add_argument("--teeth", type=int, nargs="+", action="extend", metavar="N",
                   help="engaged teeth to sweep (default: the design's)")
    p.add_argument("--loads", type=float, nargs="+", action="extend", metavar="FRACTION",
                   help="design loads to sweep as fractions of the design's (default 1)")
    _add_execution_args(p, workers_default=f"one per CPU, none for fewer than {SERIAL_BELOW} points")
    p.add_argument("--json", action="store_true", help="print the table as JSON (columns with units, rows)")
    p.add_argument("--out", metavar="FILE.csv", help="also write the table as CSV (an existing file is "
                                                     "refused unless --force)")
    p.add_argument("--force", action="store_true", help="replace an existing --out file")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=cmd_sweep)


def cmd_sweep(args: argparse.Namespace) -> int:
    """Run the sweep, print the table (or JSON) and write the CSV of ``--out``; exit 0 however
    many points are invalid (they are rows of the table)."""
    import json

    from prs_geom.sweep import print_table, sweep

    design = _load(args.design)
    _warn(design)
    execution = _execution(args, quiet=args.json or args.quiet)
    if args.out:
        check_output_file(args.out, args.force)        # refuse before the work
    result = sweep(design, starts=args.starts, rollers=args.rollers, pitch_mm=args.pitch, teeth=args.teeth,
                   loads=args.loads, workers=execution.workers, scheduler=execution.scheduler,
                   dask_workers=execution.dask_workers, progress=args.progress)
    if args.json:
        print(json.dumps(result.to_json(), indent=2))
    else:
        print_table(result)
    if args.out:
        _write_out_file(args.out, result.csv_text(), args.force)
        print(f"wrote {args.out}: {result.summary()}", file=sys.stderr)
    return EXIT_OK


def _add_harmonic_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """The sub-command ``prs-geom harmonic`` and its options."""
    p = sub.add_parser("harmonic", help="stepless harmonic friction drive calculator",
                       description="Ratio of the conical-circular-spline harmonic friction drive "
                                   "(docs/theory/harmonic.md) as a function of the axial position a.")
    p.add_argument("design", nargs="?", metavar="FILE",
                   help="harmonic design file (kind = \"harmonic\"); the worked example if omitted")
    p.add_argument("--a", type=float, nargs="+", action="extend", metavar="A",
                   help="positions a (mm) to tabulate; repeat or list several")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(func=cmd_harmonic)


def cmd_harmonic(args: argparse.Namespace) -> int:
    """Tabulate the harmonic drive's ratio over the axial position (or JSON); exit 0."""
    import numpy as np

    from prs_geom.harmonic.model import HarmonicDesign, harmonic_report

    d = HarmonicDesign() if args.design is None else _load_any(args.design)
    if not isinstance(d, HarmonicDesign):
        raise DesignError("kind", "prs", "'prs-geom harmonic' needs a design file with kind = \"harmonic\"")
    a = None
    if args.a:
        for k, v in enumerate(args.a):
            if not d.positions.min_mm <= v <= d.positions.max_mm:
                raise DesignError(f"--a (value {k + 1})", v, f"must lie in positions.min_mm .. "
                                                             f"positions.max_mm = [{d.positions.min_mm}, "
                                                             f"{d.positions.max_mm}] mm")
        a = np.array(args.a, dtype=float)
    rep = harmonic_report(d, a)
    if args.json:
        _print_json(rep)
        return EXIT_OK
    print(f"{d.name}: alpha = {rep['alpha_deg']:.4f} deg, a0 = {rep['a0_mm']:.4f} mm, infinite ratio at "
          f"a = {rep['infinite_ratio_position_mm']:.4f} mm")
    print(f"{'a mm':>8} {'beta deg':>10} {'phi deg':>9} {'contact r mm':>13} {'cone R mm':>11} "
          f"{'Delta mm':>10} {'ratio':>10}")
    for row in rep["table"]:
        print(f"{row['a_mm']:8.3f} {row['beta_deg']:10.5f} {row['phi_deg']:9.5f} {row['contact_radius_mm']:13.6f} "
              f"{row['cone_radius_mm']:11.6f} {row['radius_difference_mm']:10.6f} {row['ratio']:10.1f}")
    print(f"ratio {rep['ratio_min']:.1f} ... {rep['ratio_max']:.1f} over [{d.positions.min_mm}, "
          f"{d.positions.max_mm}] mm: speed range {rep['speed_range']:.1f}")
    for t in rep["tolerance"]:
        print(f"  ratio {t['max_ratio']:.0f} within {t['ratio_error']:.0%}: radii within +-{t['radius_tolerance_um']:.2f} um "
              f"(bore diameter band {t['diameter_band_um']:.1f} um, "
              f"{'ISO IT' + str(t['it_grade']) if t['it_grade'] else 'finer than ISO IT1'})")
    return EXIT_OK


# --------------------------------------------------------------------------- parser
#: The sub-command builders, in the order ``prs-geom --help`` lists them.
_COMMANDS = (_add_init_parser, _add_validate_parser, _add_build_parser, _add_contact_parser, _add_check_parser,
             _add_loads_parser, _add_rating_parser, _add_design_pitch_parser, _add_tolerance_parser,
             _add_sweep_parser, _add_harmonic_parser)


def make_parser() -> argparse.ArgumentParser:
    """The parser of ``prs-geom``: the top-level options and every sub-command (each built next
    to its handler, in :data:`_COMMANDS` order)."""
    parser = argparse.ArgumentParser(
        prog="prs-geom",
        description="Planetary roller screw geometry: thread meshes, contact points, load "
                    "distribution, graded-pitch design and manufacturing exports.")
    parser.add_argument("--version", action="version", version=f"prs_geom {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show tracebacks on errors (accepted anywhere on the command line)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for add_command in _COMMANDS:
        add_command(sub)
    # every command takes --quiet (no progress display; warnings and errors still print)
    for command in sub.choices.values():
        if not any("--quiet" in action.option_strings for action in command._actions):
            command.add_argument("--quiet", action="store_true",
                                 help="no progress display (warnings and errors still print)")
    return parser


#: Parameters of the library that a command-line flag sets, with that flag: a library error
#: names the parameter (or design field); :func:`main` prints the flag the user typed.
FLAG_OF_PARAMETER = {
    "workers": "--workers", "scheduler": "--scheduler", "dask_workers": "--dask-workers",
    "confidence": "--confidence", "target_ldc": "--target-ldc", "quantile": "--quantile",
    "samples": "--samples", "seed": "--seed", "distribution": "--distribution",
    "flank_um": "--flank-um", "roller_diameter_um": "--roller-diameter-um",
    "screw_eccentricity_um": "--eccentricity-um", "nut_eccentricity_um": "--eccentricity-um",
    "lead_um": "--lead-um", "temperature_k": "--temperature-k", "load_fractions": "--load-fraction",
}


def flag_named(exc: DesignError) -> DesignError:
    """``exc`` under the command-line flag of its field (:data:`FLAG_OF_PARAMETER`; an index
    such as ``[2]`` is kept), or ``exc`` itself when no flag sets that field."""
    parameter, bracket, index = exc.field.partition("[")
    flag = FLAG_OF_PARAMETER.get(parameter)
    return exc if flag is None else exc.renamed(flag + bracket + index)


def _one_line(exc: OSError) -> str:
    """``path: reason`` of an OS error, as one line."""
    path = exc.filename if exc.filename is not None else "(unknown path)"
    extra = f" -> {exc.filename2}" if exc.filename2 is not None else ""
    return f"{path}{extra}: {exc.strerror or exc}"


def _on_stop_signal(signum, frame):
    """SIGINT raises KeyboardInterrupt, SIGTERM :class:`Terminated`. The first of them stops the
    command; any later one (a second Ctrl-C, or the copy a worker forwards when the whole
    process group got it) is ignored, so that it cannot cut short the clean-up that kills the
    workers and removes the temporary output."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, signal.SIG_IGN)
    if signum == signal.SIGINT:
        raise KeyboardInterrupt
    raise Terminated(signum)


def _stop_on_signals() -> dict:
    """Install :func:`_on_stop_signal` for SIGINT and SIGTERM; the handlers it replaced, to be
    restored (none outside the main thread, where signals are left alone)."""
    previous = {}
    try:
        for sig in (signal.SIGINT, signal.SIGTERM):
            # a process started with SIGINT ignored (nohup, some test runners) keeps ignoring it
            if signal.getsignal(sig) is not signal.SIG_IGN:
                previous[sig] = signal.signal(sig, _on_stop_signal)
    except ValueError:  # not the main thread
        return {}
    return previous


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``prs-geom argv`` (default ``sys.argv[1:]``) and return its exit code (module docstring)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    # --debug is accepted anywhere, before or after the sub-command
    debug = "--debug" in argv
    argv = [a for a in argv if a != "--debug"]
    parser = make_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 0 for --help/--version, 2 for usage errors
        return int(exc.code or 0)
    args.debug = debug
    # one progress display per command, on stderr (prs_geom.runtime.progress); none with --quiet or
    # --json. It starts with the first stage a command reports, so quick commands show nothing.
    display = None
    if not (getattr(args, "quiet", False) or getattr(args, "json", False)):
        display = ConsoleProgress(default_stage=args.command)
    args.progress = display if display is not None else silent

    previous = _stop_on_signals()

    def fail(code: int, message: str) -> int:
        if debug:
            raise
        print(f"error: {message}", file=sys.stderr)
        return code

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DesignWarning)
            try:
                code = args.func(args)
            except BaseException:
                if display is not None:
                    display.close(success=False)
                raise
            if display is not None:
                display.close(success=True)
            return code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_SIGINT
    except Terminated:
        print("interrupted", file=sys.stderr)
        return EXIT_SIGTERM
    except DesignError as exc:
        return fail(EXIT_INPUT, str(flag_named(exc)))
    except (UsageError, OutputRefused) as exc:
        return fail(EXIT_INPUT, str(exc))
    except (EnvironmentFailure, ResourceLimitError) as exc:
        return fail(EXIT_ENVIRONMENT, str(exc))
    except OSError as exc:
        return fail(EXIT_ENVIRONMENT, _one_line(exc))
    except MemoryError:
        return fail(EXIT_ENVIRONMENT, "out of memory (lower --memory-budget so that prs-geom refuses "
                                      "such jobs up front, or coarsen mesh.chord_tolerance_mm)")
    except PRSGeomError as exc:
        return fail(EXIT_FOUND, str(exc))
    except Exception as exc:  # a bug: one line, the traceback with --debug
        return fail(EXIT_INTERNAL, f"internal error {type(exc).__name__}: {exc} (run with --debug for "
                                   f"the traceback and please report it)")
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def entry_point() -> None:
    """The console script: :func:`main` as the process exit code."""
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    entry_point()
