"""Command-line interface ``prs-geom``.

Exit codes: 0 success; 1 the analysis found a problem (e.g. interference) or a solver
failed; 2 bad input (the message names the field, the value and the rule); 3 a
subcommand not available in this version. Without ``--debug`` no traceback is shown.
"""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Callable, Sequence

from . import __version__
from .design import PRSDesign, default_design
from .designio import dumps_toml, load_design
from .errors import DesignError, DesignWarning, PRSGeomError
from .progress import StderrProgress, silent

EXIT_OK, EXIT_FOUND, EXIT_INPUT, EXIT_UNAVAILABLE = 0, 1, 2, 3


class UsageError(PRSGeomError):
    """Bad command-line usage (exit code 2)."""


class Unavailable(PRSGeomError):
    """A subcommand whose stage is not in this version (exit code 3)."""


def _load(path: str | None) -> PRSDesign:
    if path is None:
        return default_design()
    return load_design(path)


def _warn(design: PRSDesign) -> None:
    for msg in design.sizing_warnings():
        print(f"warning: {msg}", file=sys.stderr)


# --------------------------------------------------------------------------- commands
def cmd_init(args: argparse.Namespace) -> int:
    text = dumps_toml(default_design(), header=(
        "prs_geom design file (TOML). Units: mm, N, MPa; angles in degrees.\n"
        "Every key is optional; omitted keys take the built-in default.\n"
        "Teeth are numbered 1..n from the loaded end."))
    if args.out:
        Path(args.out).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    return EXIT_OK


def cmd_build(args: argparse.Namespace) -> int:
    from .pipeline import build

    design = _load(args.design)
    _warn(design)
    out = Path(args.out) if args.out else Path("exports") / design.name
    progress = silent if args.quiet else StderrProgress()
    report = build(design, out, progress=progress)
    if not args.quiet:
        print(f"wrote {len(report['files'])} files to {out}", file=sys.stderr)
    print(str(out / "report.json"))
    return EXIT_OK


def _unavailable(what: str) -> Callable[[argparse.Namespace], int]:
    def run(args: argparse.Namespace) -> int:
        _load(getattr(args, "design", None))
        raise Unavailable(f"'{what}' is not available in prs_geom {__version__} yet")
    return run


# --------------------------------------------------------------------------- parser
def make_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="prs-geom",
        description="Planetary roller screw geometry: thread meshes, contact points, load "
                    "distribution, graded-pitch design and manufacturing exports.")
    parser.add_argument("--version", action="version", version=f"prs_geom {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True

    p = sub.add_parser("init", help="write the default design as a commented TOML file",
                       description="Write the built-in default design as a commented TOML "
                                   "design file (to stdout, or to --out).")
    p.add_argument("--out", metavar="FILE", help="file to write instead of stdout")
    p.set_defaults(func=cmd_init)

    def design_arg(q: argparse.ArgumentParser) -> None:
        q.add_argument("design", nargs="?", metavar="DESIGN",
                       help="design file (.toml or .json); the built-in default design if omitted")

    p = sub.add_parser("build", help="run every stage and write all exports and report.json",
                       description="Run every stage on a design and write all exports plus "
                                   "report.json into an output folder, atomically: a failed "
                                   "run leaves an earlier output untouched.")
    design_arg(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default exports/<design name>)")
    p.add_argument("--quiet", action="store_true", help="no progress output")
    p.set_defaults(func=cmd_build)

    for name, text in (
        ("contact", "screw-roller and roller-nut contact points and the corrected screw diameter"),
        ("loads", "load distribution over the thread teeth"),
        ("design-pitch", "pitch lists for equal (or target) load sharing"),
        ("check", "interference check of the assembly (exit 1 when parts interfere)"),
        ("harmonic", "stepless harmonic friction drive calculator"),
    ):
        p = sub.add_parser(name, help=text, description=text[0].upper() + text[1:] + ".")
        design_arg(p)
        p.set_defaults(func=_unavailable(name))
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = make_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: 0 for --help/--version, 2 for usage errors
        return int(exc.code or 0)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DesignWarning)
            return args.func(args)
    except DesignError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except (UsageError,) as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except Unavailable as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_UNAVAILABLE
    except PRSGeomError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FOUND


def entry_point() -> None:
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    entry_point()
