"""Shared by the CLI-level tests: run the CLI in-process and write TOML design files."""
import io
import math
from contextlib import redirect_stderr, redirect_stdout

from prs_geom import cli
from prs_geom.model.io import toml_string

__all__ = ["run", "toml_value", "to_toml"]


def run(argv):
    """(exit code, stdout, stderr) of ``prs-geom argv``."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()


def toml_value(v) -> str:
    """A value in TOML spelling, including the invalid ones the tests feed (nan, inf, nested)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return toml_string(v)
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{toml_string(str(k))} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def to_toml(data: dict) -> str:
    """TOML text of a nested dict (keys quoted, one table per sub-dict)."""
    lines = []

    def emit(tbl: dict, prefix: str) -> None:
        scal = {k: v for k, v in tbl.items() if not isinstance(v, dict)}
        if prefix:
            lines.append(f"[{prefix}]")
        lines.extend(f"{toml_string(str(k))} = {toml_value(v)}" for k, v in scal.items())
        for k, v in tbl.items():
            if isinstance(v, dict):
                emit(v, f"{prefix}.{toml_string(str(k))}" if prefix else toml_string(str(k)))

    emit(data, "")
    return "\n".join(lines) + "\n"
