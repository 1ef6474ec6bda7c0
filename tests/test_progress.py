"""The console progress display (prs_geom.runtime.progress), driven by a fake clock.

The real gaps and the interrupt delay of a real build are measured by
``benchmarks/bench_build.py``; here the display's rules are checked in fake time.
"""
from __future__ import annotations

import io
import re

from prs_geom.runtime.progress import ConsoleProgress, begin_stage, end_stage, silent, unwatch_job, watch_job

LINE = re.compile(r"^\[\s*([0-9.]+) s\] (.*)$")


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def _display(clock: FakeClock) -> tuple[ConsoleProgress, io.StringIO]:
    out = io.StringIO()
    return ConsoleProgress(stream=out, live=False, clock=clock, threaded=False), out


def _stamped(text: str) -> list[tuple[float, str]]:
    return [(float(m.group(1)), m.group(2)) for m in map(LINE.match, text.splitlines()) if m]


def test_a_line_at_least_every_two_seconds_while_a_stage_runs():
    clock = FakeClock()
    display, out = _display(clock)
    display.start()
    display.begin("meshes")
    # a stage that reports nothing for 10 s, then counts slowly: ticks every 0.25 s of fake time
    for k in range(200):
        clock.now += 0.25
        if k >= 40 and k % 8 == 0:
            display("meshes", k // 8, 20)
        display.tick()
    display.end("meshes")
    stamps = [t for t, _ in _stamped(out.getvalue())]
    assert stamps[0] == 0.0
    gaps = [b - a for a, b in zip(stamps, stamps[1:])]
    assert max(gaps) <= 2.0 and stamps[-1] >= 50.0 - 2.0, stamps
    # but not a flood: one line a second at most while only a count moves
    assert min(gaps) >= 1.0 - 0.11 and len(stamps) <= 52   # 0.1 s: the stamps are rounded
    # the count is shown as it moves
    assert any(text == "meshes: 20/20" or text.endswith("/20") for _, text in _stamped(out.getvalue()))


def test_worker_jobs_are_polled_and_shown_beside_the_stage():
    clock = FakeClock()
    display, out = _display(clock)
    reported = [None]
    display.begin("meshes")
    watch_job(display, "checks", lambda: reported[0])
    clock.now += 2.0
    display.tick()
    assert _stamped(out.getvalue())[-1][1] == "meshes | in workers: checks"
    reported[0] = ("interference pairs", 12, 40)
    clock.now += 1.0
    display.tick()
    assert _stamped(out.getvalue())[-1][1] == "meshes | checks (worker): interference pairs 12/40"
    unwatch_job(display, "checks", 7.5)
    display.end("meshes")
    table = display.table()
    assert re.search(r"^checks \(worker\)\s+7\.50$", table, re.M), table


def test_stage_table_at_the_end_with_each_stage_time():
    clock = FakeClock()
    display, out = _display(clock)
    for name, seconds in (("design", 0.5), ("loads", 3.25), ("meshes", 12.0)):
        begin_stage(display, name)
        clock.now += seconds
        end_stage(display, name)
    display.close(success=True)
    text = out.getvalue()
    table = text[text.index("stage"):].splitlines()
    assert table[0].split() == ["stage", "time", "(s)"]
    rows = {line.rsplit(None, 1)[0].strip(): float(line.rsplit(None, 1)[1]) for line in table[1:]}
    assert rows == {"design": 0.5, "loads": 3.25, "meshes": 12.0, "total (wall)": 15.75}


def test_no_table_after_a_failure_and_nothing_for_a_command_without_stages():
    clock = FakeClock()
    display, out = _display(clock)
    display.begin("meshes")
    clock.now += 1
    display.close(success=False)
    assert "time (s)" not in out.getvalue()
    quiet, out2 = _display(clock)
    quiet.close(success=True)
    assert out2.getvalue() == ""
    # a quick command shows its stage but no table
    quick, out3 = _display(clock)
    quick.begin("loads")
    clock.now += 0.2
    quick.close(success=True)
    assert out3.getvalue() == "[    0.0 s] loads\n"


def test_plain_callbacks_ignore_the_stage_protocol():
    # library code calls these on whatever callback it was given
    begin_stage(silent, "x")
    end_stage(silent, "x")
    watch_job(silent, "x", lambda: None)
    unwatch_job(silent, "x", 1.0)
    calls = []
    begin_stage(lambda *a: calls.append(a), "x")
    assert calls == []


def test_live_display_draws_with_rich_and_clears_its_rows(capsys):
    out = io.StringIO()
    display = ConsoleProgress(stream=out, live=True, threaded=False, summary_min_s=0.0)
    display.begin("loads")
    display("loads", 3, 9)
    print("the command's result")   # stdout stays the command's, even under a live display
    display.tick()
    display.close(success=True)
    assert capsys.readouterr().out == "the command's result\n"
    text = out.getvalue()
    assert "the command's result" not in text
    # the transient live rows are gone; the stage table stays
    assert "stage" in text and re.search(r"^loads\s+[0-9.]+$", text, re.M)


class Recorder:
    """A progress object that records what a build tells it (the stage protocol)."""

    def __init__(self) -> None:
        self.begun: list[str] = []
        self.watched: dict[str, object] = {}
        self.unwatched: dict[str, float | None] = {}
        self.last: dict[str, object] = {}

    def __call__(self, stage: str, done: int, total: int) -> None:
        pass

    def begin(self, stage: str) -> None:
        self.begun.append(stage)

    def end(self, stage: str) -> None:
        assert self.begun[-1] == stage

    def watch(self, name: str, poll) -> None:
        self.watched[name] = poll

    def unwatch(self, name: str, seconds: float | None = None) -> None:
        self.unwatched[name] = seconds
        self.last[name] = self.watched[name]()   # the job's last report, read when it is taken


def test_a_build_announces_its_stages_and_every_worker_job(tmp_path, monkeypatch):
    """The pipeline's wiring: every stage begun in order, every job started in a worker
    watched and, once its result is taken, unwatched with its own time; the jobs that
    count (checks, mesh checks, drawings) report their last count as complete."""
    import prs_geom as pg
    from prs_geom.model.design import MeshSettings, PRSDesign, Roller, Thread
    from prs_geom.pipeline import STAGES

    monkeypatch.setenv("PRS_GEOM_WORKERS", "2")
    tiny = PRSDesign(name="tiny", thread=Thread(engaged_teeth=3), roller=Roller(count=3),
                     mesh=MeshSettings(chord_tolerance_mm=0.05))
    rec = Recorder()
    report = pg.build(tiny, tmp_path / "out", progress=rec)
    assert rec.begun == [name for name, _ in STAGES]
    jobs = {"checks", "mesh checks", "drawings", "load plots", "rating plots"}
    assert set(rec.watched) == jobs and set(rec.unwatched) == jobs
    assert all(seconds is not None and seconds > 0 for seconds in rec.unwatched.values())
    # the job's own time is what report.json books to its stage
    assert rec.unwatched["drawings"] <= report["timings_s"]["manufacturing"] + 1e-9
    for name in ("checks", "mesh checks", "drawings"):
        stage, done, total = rec.last[name]
        assert done == total > 0, (name, stage, done, total)
