"""Background jobs of a build (prs_geom.runtime.pool)."""
from __future__ import annotations

import pickle

import pytest

from prs_geom.runtime.pool import Background, default_workers
from prs_geom.model.errors import DesignError


def _square(x: float) -> float:
    return x * x


def _fail(field: str) -> None:
    raise DesignError(field, 3.5, "must be below 1")


@pytest.mark.parametrize("workers", [0, 1])
def test_jobs_return_their_values_and_time(workers):
    with Background(workers) as bg:
        jobs = [bg.submit(_square, x) for x in (2.0, 3.0)]
        assert [j.result() for j in jobs] == [4.0, 9.0]
        assert all(j.seconds >= 0.0 for j in jobs)


@pytest.mark.parametrize("workers", [0, 1])
def test_a_worker_error_comes_back_with_its_type_and_field(workers):
    """A design error raised in a worker reaches the CLI as a DesignError (exit code 2 and
    the field named), not as a broken pool."""
    with Background(workers) as bg:
        with pytest.raises(DesignError) as info:
            bg.submit(_fail, "roller.count").result()
    assert info.value.field == "roller.count" and info.value.value == 3.5
    assert str(info.value) == "roller.count = 3.5: must be below 1"


def test_design_errors_pickle():
    err = DesignError.about_file("x.toml", "not TOML")
    back = pickle.loads(pickle.dumps(err))
    assert type(back) is DesignError and str(back) == str(err) and back.field == err.field


def test_worker_count_from_the_environment(monkeypatch):
    monkeypatch.setenv("PRS_GEOM_WORKERS", "0")
    assert default_workers() == 0
    monkeypatch.setenv("PRS_GEOM_WORKERS", "3")
    assert default_workers() == 3
    for bad in ("-1", "two"):
        monkeypatch.setenv("PRS_GEOM_WORKERS", bad)
        with pytest.raises(DesignError) as info:
            default_workers()
        assert info.value.field == "PRS_GEOM_WORKERS" and "whole number" in str(info.value)
    monkeypatch.delenv("PRS_GEOM_WORKERS")
    assert default_workers() in (0, 2)


def test_bad_worker_count_exits_2_and_writes_nothing(tmp_path, monkeypatch):
    from cli_helpers import run

    monkeypatch.setenv("PRS_GEOM_WORKERS", "many")
    code, out, err = run(["build", "--out", str(tmp_path / "x"), "--quiet"])
    assert code == 2 and "PRS_GEOM_WORKERS" in err
    assert not (tmp_path / "x").exists()


def test_a_design_that_fits_only_serially_builds_without_workers(tmp_path, monkeypatch):
    """The workers' memory adds to the main process's; a build whose estimate fits the
    budget only without them runs serially instead of being refused."""
    from prs_geom import pipeline
    from prs_geom.mesh.budget import estimate
    from prs_geom.model.errors import ResourceLimitError
    from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread

    d = PRSDesign(name="small", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                  mesh=MeshSettings(chord_tolerance_mm=0.05))
    serial, parallel = estimate(d).peak_bytes, estimate(d, workers=2).peak_bytes
    assert parallel > serial
    seen = []
    original = pipeline.run_stages

    def spy(*args, **kwargs):
        seen.append(kwargs.get("workers"))
        return original(*args, **kwargs)

    monkeypatch.setattr(pipeline, "run_stages", spy)
    monkeypatch.setenv("PRS_GEOM_WORKERS", "2")
    pipeline.build(d, tmp_path / "a", memory_budget=int(0.5 * (serial + parallel)))
    assert seen == [0] and (tmp_path / "a" / "report.json").exists()
    pipeline.build(d, tmp_path / "b", memory_budget=int(1.01 * parallel))
    assert seen == [0, 2]
    with pytest.raises(ResourceLimitError):
        pipeline.build(d, tmp_path / "c", memory_budget=int(0.99 * serial))
    assert not (tmp_path / "c").exists()
