import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
# every build in the tests runs under an explicit memory budget, whatever the machine has free
os.environ.setdefault("PRS_GEOM_MEMORY_BUDGET", "6G")
# the suite runs its test files on every core (pytest-xdist): builds do their work in their own
# process rather than spawning workers of their own; tests/test_golden.py runs both ways
os.environ.setdefault("PRS_GEOM_WORKERS", "0")
# builds in the tests compute every stage: the stage cache is on only in the tests of the
# cache itself (tests/test_build_cache.py), which set PRS_GEOM_STAGE_CACHE themselves
os.environ.setdefault("PRS_GEOM_STAGE_CACHE", "0")
# the finite-element matrix cache and the stage cache of a test run go to a folder of their
# own, never to the user's ~/.cache (each xdist worker has its own; removed at exit)
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


# --------------------------------------------------------------------------- shared builds
#: Designs built once per test run for the tests that only read a build's outputs.
SHARED_DESIGNS = {"default": None, "graded": "graded-pitch.toml", "harmonic": "harmonic.toml"}


def _shared_build(name: str, tmp_path_factory) -> "SharedBuild":
    """Build ``name`` once per test run, shared by every xdist worker.

    The first worker to ask builds into a folder beside the workers' own temporary folders,
    under an exclusive file lock; the others wait on the lock and read the finished folder.
    The folder is read-only by contract: a test that changes outputs builds its own.
    """
    import fcntl
    import json
    import pickle
    from pathlib import Path

    from prs_geom import pipeline
    from prs_geom.model.design import default_design

    base = tmp_path_factory.getbasetemp()
    root = base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base
    out = root / f"shared-build-{name}"
    with open(root / f"shared-build-{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        returned_file = root / f"shared-build-{name}.returned.pickle"
        if not returned_file.is_file():
            example = SHARED_DESIGNS[name]
            design = default_design() if example is None else pipeline.load_any_design(
                Path(__file__).resolve().parents[1] / "examples" / example)
            returned = pipeline.build(design, out)
            # the report as build() returned it, types and all, for the tests of that return value
            returned_file.write_bytes(pickle.dumps(returned))
    report = json.loads((out / pipeline.REPORT_NAME).read_text(encoding="utf-8"))
    return SharedBuild(out=out, report=report, returned=pickle.loads(returned_file.read_bytes()))


class SharedBuild:
    """A finished build shared by the tests of one run: its folder, its report.json and the
    report ``build()`` returned."""

    def __init__(self, out, report, returned):
        self.out = out
        self.report = report
        self.returned = returned


@pytest.fixture(scope="session")
def default_build(tmp_path_factory) -> SharedBuild:
    """The built-in default design, built once per test run (read-only)."""
    return _shared_build("default", tmp_path_factory)


@pytest.fixture(scope="session")
def graded_build(tmp_path_factory) -> SharedBuild:
    """examples/graded-pitch.toml, built once per test run (read-only)."""
    return _shared_build("graded", tmp_path_factory)


@pytest.fixture(scope="session")
def harmonic_build(tmp_path_factory) -> SharedBuild:
    """examples/harmonic.toml, built once per test run (read-only)."""
    return _shared_build("harmonic", tmp_path_factory)


# --------------------------------------------------------------------------- markers
#: Markers that keep a test out of the quick subset (``pytest -m quick``).
SLOW_MARKERS = ("heavy", "golden", "docs", "slow")


#: Test files whose tests build whole designs, run subprocesses or browsers: all ``slow``.
SLOW_FILES = {
    "test_api", "test_background", "test_exports", "test_fe_compliance", "test_fuzz", "test_html",
    "test_interference", "test_interference_cache", "test_interference_windows", "test_interrupts",
    "test_mechanism", "test_pipeline", "test_report_schema", "test_safety", "test_scene", "test_step",
    "test_studies",
}
#: (file, test-name prefix) of the slow tests in otherwise quick files, as measured with
#: ``--durations=0`` (each takes seconds: a build, a sampled sweep, a convergence study).
SLOW_TESTS = {
    ("test_actuator_meshes", "test_default_assembly_places_the_actuator_parts"),
    ("test_architecture", "test_theoretical_diameter_is_solved_once_per_build"),
    ("test_architecture", "test_package_import_is_light"),
    ("test_broad_phase", "test_broad_phase_and_slices"),
    ("test_broad_phase", "test_theoretical_screw_check"),
    ("test_assembly", "test_end_gears_mesh_with_the_ring_gear"),
    ("test_cli", "test_failing_build_leaves_earlier_output_unchanged"),
    ("test_cli", "test_console_script_exit_code"),
    ("test_designio", "test_init_then_build_round_trips"),
    ("test_drawing", "test_dxf_bytes_are_deterministic"),
    ("test_fcl_verify", "test_fcl_check_agrees_or_explains_on_sampled_designs"),
    ("test_fe", "test_mesh_convergence_three_levels"),
    ("test_fe", "test_fe_calibrated_width_supports"),
    ("test_fe_cache", "test_key_follows_material_geometry_and_code"),
    ("test_harmonic", "test_harmonic_outputs_files_and_report_keys"),
    ("test_harmonic", "test_build_harmonic_writes_exports"),
    ("test_harmonic", "test_report_html_viewer_draws"),
    ("test_injection", "test_build_"),
    ("test_load_solver", "test_rollers_agree_with_the_other_formulations"),
    ("test_machining", "test_csv_reads_back_to_report_numbers"),
    ("test_mesh", "test_deviation_within_tolerance"),
    ("test_mesh", "test_sampled_designs_give_closed_accurate_meshes"),
    ("test_mesh", "test_fine_tolerance_assembly_meshes"),
    ("test_numeric_guards", "test_build_of_every_accepted_value"),
    ("test_plots", "test_plot_in_a_worker_process"),
    ("test_progress", "test_a_build_announces_its_stages"),
    ("test_scaleout", "test_local_dask_cluster"),
    ("test_scaleout", "test_dask_cluster_by_address"),
    ("test_sweep", "test_joblib_equals_serial"),
    ("test_scaleout", "test_joblib_equals_serial"),
    ("test_tolerance", "test_build_of_toleranced_design"),
    ("test_tolerance", "test_synthesis_meets_target_in_independent_rerun"),
}
#: The documentation tests: pages rendered, the site built, docstring examples run.
DOCS_FILES = {"test_docs", "test_api_examples"}
DOCS_TESTS = {("test_architecture", "test_docs_build_strict")}


#: Rough cost (s on one core) of the longest test files, from a --durations=0 run. The
#: suite sends the costliest files to the xdist workers first (--dist loadfile hands out
#: files in collection order), so that no worker is left running a long file alone at the end.
FILE_COST_S = {
    "test_step": 185, "test_build_cache": 88, "test_safety": 79, "test_api": 58, "test_html": 56,
    "test_golden": 56, "test_fe_compliance": 50, "test_interrupts": 36,
    "test_numeric_guards": 35, "test_fuzz": 31, "test_report_schema": 29, "test_scene": 27, "test_cli": 22,
    "test_api_examples": 22, "test_mesh": 21, "test_build_only": 20, "test_injection": 20,
    "test_architecture": 19, "test_background": 19, "test_machining": 18, "test_tolerance": 17, "test_fe": 17,
    "test_pipeline": 16, "test_designio": 14, "test_parts": 13, "test_exports": 11, "test_drawing": 10,
    "test_studies": 10, "test_interference": 10, "test_interference_windows": 10, "test_broad_phase": 13,
}


def _listed(item, files: set[str], tests: set[tuple[str, str]]) -> bool:
    """Whether ``item`` is in one of ``files`` or is one of ``tests`` (file, name prefix)."""
    module = item.path.stem
    return module in files or any(module == f and item.name.startswith(p) for f, p in tests)


def pytest_collection_modifyitems(config, items):
    """Send the costliest files first (:data:`FILE_COST_S`); mark the measured slow tests
    ``slow`` (:data:`SLOW_FILES`, :data:`SLOW_TESTS`) and every test without a slow marker
    ``quick``: ``pytest -m quick -n auto`` is the day-to-day subset (docs/development.md)."""
    # stable: the tests of one file keep their order
    items.sort(key=lambda item: -FILE_COST_S.get(item.path.stem, 0))
    for item in items:
        if _listed(item, SLOW_FILES, SLOW_TESTS):
            item.add_marker(pytest.mark.slow)
        if _listed(item, DOCS_FILES, DOCS_TESTS):
            item.add_marker(pytest.mark.docs)
        if not any(item.get_closest_marker(m) for m in SLOW_MARKERS):
            item.add_marker(pytest.mark.quick)
