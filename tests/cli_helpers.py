"""Run the CLI in-process and capture its output (shared by the CLI-level tests)."""
import io
from contextlib import redirect_stderr, redirect_stdout

from prs_geom import cli


def run(argv):
    """(exit code, stdout, stderr) of ``prs-geom argv``."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = cli.main(argv)
    return code, out.getvalue(), err.getvalue()
