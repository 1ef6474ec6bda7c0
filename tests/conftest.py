import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
# every build in the tests runs under an explicit memory budget, whatever the machine has free
os.environ.setdefault("PRS_GEOM_MEMORY_BUDGET", "6G")
# the suite runs its test files on every core (pytest-xdist): builds do their work in their own
# process rather than spawning workers of their own; tests/test_golden.py runs both ways
os.environ.setdefault("PRS_GEOM_WORKERS", "0")
# the finite-element matrix cache of a test run goes to a folder of its own, never to the
# user's ~/.cache (each xdist worker has its own; removed at exit)
if "PRS_GEOM_CACHE" not in os.environ:
    import atexit
    import shutil
    import tempfile

    _cache = tempfile.mkdtemp(prefix="prs-geom-test-cache-")
    os.environ["PRS_GEOM_CACHE"] = _cache
    atexit.register(shutil.rmtree, _cache, True)

from hypothesis import HealthCheck, settings  # noqa: E402

settings.register_profile("default", deadline=None, suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("ci", deadline=None, suppress_health_check=[HealthCheck.too_slow],
                          derandomize=True)
settings.load_profile("ci" if os.environ.get("CI") else "default")


import pytest  # noqa: E402


@pytest.fixture(scope="session")
def heavy_scale() -> str:
    """'full' with PRS_HEAVY=full, else 'reduced' (what CI runs for tests marked heavy)."""
    return "full" if os.environ.get("PRS_HEAVY") == "full" else "reduced"


@pytest.fixture(scope="session", autouse=True)
def validate_every_build():
    """Every successful ``prs_geom.pipeline.build`` in the suite is checked against the report
    schema: the returned report and the report.json it wrote (prs_geom/report_schema.py).

    Patches ``prs_geom.pipeline.build`` (the CLI imports it at call time) and the ``build``
    name of every test module that imported it with ``from prs_geom.pipeline import build``;
    session-scoped so that builds in module-scoped fixtures are checked too. Builds in
    subprocesses are not seen.
    """
    import functools
    import json
    from pathlib import Path

    from prs_geom import pipeline
    from prs_geom.exports.report_schema import validate_report

    original = pipeline.build

    @functools.wraps(original)
    def checked_build(design, out_dir, *args, **kwargs):
        report = original(design, out_dir, *args, **kwargs)
        validate_report(report)
        with open(Path(out_dir) / pipeline.REPORT_NAME, encoding="utf-8") as f:
            validate_report(json.load(f))
        return report

    tests_dir = Path(__file__).resolve().parent
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(pipeline, "build", checked_build)
        for mod in list(sys.modules.values()):
            path = getattr(mod, "__file__", None)
            if path and getattr(mod, "build", None) is original and tests_dir in Path(path).resolve().parents:
                mp.setattr(mod, "build", checked_build)
        yield checked_build
