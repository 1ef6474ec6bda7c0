"""Progress of long work: the callback protocol and the console display of a command.

Library code reports progress through a plain callback, ``progress(stage, done, total)``
(:data:`ProgressFn`; :func:`silent` prints nothing). A command shows it with one
:class:`ConsoleProgress` per run, on standard error:

* on a terminal, a live display drawn by `rich <https://github.com/Textualize/rich>`_ (a
  well-kept library that owns the terminal handling: cursor movement, redrawing, width,
  colour detection): one row per stage with a spinner, a bar and count where the stage
  reports them, and the elapsed time, plus a row per job running in a worker process;
* elsewhere (a log file, a pipe, CI), plain lines ``[  12.3 s] meshes 3/9 | checks
  (worker): interference 12/40``, one when something changed (at most every
  :attr:`ConsoleProgress.min_interval_s`) and at least every
  :attr:`ConsoleProgress.heartbeat_s` while a stage runs, so that a silent gap never
  exceeds 2 s;
* at the end, a table of the stage times (wall time of each stage in this process, and
  of each job in a worker).

The display is driven by a daemon thread that calls :meth:`ConsoleProgress.tick`; tests
call :meth:`~ConsoleProgress.tick` themselves with a fake clock. Stages are announced with
:meth:`~ConsoleProgress.begin` and :meth:`~ConsoleProgress.end`; work running in a worker
process is shown through :meth:`~ConsoleProgress.watch` with a function that polls the
worker's latest progress (:meth:`prs_geom.runtime.pool.Job.poll`). Library code calls the
module functions :func:`begin_stage`, :func:`end_stage`, :func:`watch_job` and
:func:`unwatch_job`, which do nothing for a plain callback.

Leaf module: it imports nothing of prs_geom; rich is imported when a live display starts.
"""
from __future__ import annotations

import sys
import threading
import time
from dataclasses import dataclass, field
from typing import Any, Callable, TextIO

__all__ = ["ProgressFn", "silent", "ConsoleProgress", "begin_stage", "end_stage", "watch_job", "unwatch_job"]

#: A progress callback: (stage, done, total).
ProgressFn = Callable[[str, int, int], None]
#: What a watched worker job reports: ``(stage, done, total)`` or None (nothing yet).
PollFn = Callable[[], "tuple[str, int, int] | None"]


def silent(stage: str, done: int, total: int) -> None:
    """A progress callback that prints nothing."""


def begin_stage(progress: Any, stage: str) -> None:
    """Tell ``progress`` that ``stage`` starts (a no-op for a plain callback)."""
    fn = getattr(progress, "begin", None)
    if fn is not None:
        fn(stage)


def end_stage(progress: Any, stage: str) -> None:
    """Tell ``progress`` that ``stage`` ended (a no-op for a plain callback)."""
    fn = getattr(progress, "end", None)
    if fn is not None:
        fn(stage)


def watch_job(progress: Any, name: str, poll: PollFn) -> None:
    """Show the worker job ``name`` on ``progress`` (a no-op for a plain callback)."""
    fn = getattr(progress, "watch", None)
    if fn is not None:
        fn(name, poll)


def unwatch_job(progress: Any, name: str, seconds: float | None = None) -> None:
    """The worker job ``name`` has finished, after ``seconds`` of its own work (a no-op for
    a plain callback)."""
    fn = getattr(progress, "unwatch", None)
    if fn is not None:
        fn(name, seconds)


@dataclass
class _Row:
    """One stage or worker job on the display."""

    name: str
    started: float
    in_worker: bool = False
    poll: PollFn | None = None
    label: str = ""
    done: int = 0
    total: int = 0
    ended: float | None = None
    task: Any = None   # the rich task id in a live display

    def status(self) -> str:
        """``name[ (worker)][: label done/total]``."""
        text = f"{self.name} (worker)" if self.in_worker else self.name
        if self.total:
            sub = f"{self.label} " if self.label and self.label != self.name else ""
            text += f": {sub}{self.done}/{self.total}"
        return text


@dataclass
class ConsoleProgress:
    """One progress display of a long command, on ``stream`` (standard error by default).

    Parameters
    ----------
    stream : text stream, optional
        Where to draw (default ``sys.stderr``).
    live : bool, optional
        A live rich display (True) or plain lines (False); default: live when ``stream``
        is a terminal.
    clock : callable
        Seconds, monotonic (``time.monotonic``; tests pass a fake clock).
    threaded : bool
        Start a daemon thread that calls :meth:`tick` every :attr:`tick_s` seconds.
    summary : bool
        Print the table of stage times when the display closes after success (for commands
        that ran at least :attr:`summary_min_s`).
    """

    stream: TextIO | None = None
    live: bool | None = None
    clock: Callable[[], float] = time.monotonic
    threaded: bool = True
    summary: bool = True
    #: plain lines: at most one per this many seconds when only a count moved (s)
    min_interval_s: float = 1.0
    #: plain lines: at least one per this many seconds while a stage runs (s)
    heartbeat_s: float = 1.0
    #: seconds between two ticks of the display thread
    tick_s: float = 0.25
    #: the stage-time table is printed for commands that ran at least this long (s)
    summary_min_s: float = 1.0
    #: the stage that progress reported outside any announced stage belongs to (the
    #: command's name); None: the reported stage name itself
    default_stage: str | None = None
    _rows: list[_Row] = field(default_factory=list, init=False)
    _current: _Row | None = field(default=None, init=False)
    _jobs: dict[str, _Row] = field(default_factory=dict, init=False)
    _t0: float = field(default=0.0, init=False)
    _last_line: float = field(default=float("-inf"), init=False)
    _last_status: str = field(default="", init=False)
    _lock: Any = field(default_factory=threading.RLock, init=False)
    _stop: Any = field(default_factory=threading.Event, init=False)
    _thread: Any = field(default=None, init=False)
    _rich: Any = field(default=None, init=False)
    _started: bool = field(default=False, init=False)

    # ---------------------------------------------------------------- life cycle
    def __post_init__(self) -> None:
        if self.stream is None:
            self.stream = sys.stderr
        if self.live is None:
            isatty = getattr(self.stream, "isatty", None)
            self.live = bool(isatty and isatty())

    def __enter__(self) -> "ConsoleProgress":
        self.start()
        return self

    def __exit__(self, exc_type: Any, *exc: object) -> None:
        self.close(success=exc_type is None)

    def start(self) -> None:
        """Start the clock, the live display and the display thread."""
        if self._started:
            return
        self._started = True
        self._t0 = self.clock()
        if self.live:
            from rich.console import Console
            from rich.progress import (BarColumn, MofNCompleteColumn, Progress, SpinnerColumn, TextColumn,
                                       TimeElapsedColumn)

            console = Console(file=self.stream, stderr=self.stream is sys.stderr)
            # transient: the live rows go when the command ends; the stage table stays
            # stdout is the command's result (a table a user redirects to a file): rich must
            # not route it through the display's console, which writes to stderr
            self._rich = Progress(SpinnerColumn(), TextColumn("{task.description}"), BarColumn(),
                                  MofNCompleteColumn(), TimeElapsedColumn(), console=console, transient=True,
                                  refresh_per_second=4, redirect_stdout=False)
            self._rich.start()
        if self.threaded:
            self._thread = threading.Thread(target=self._run, name="prs-geom-progress", daemon=True)
            self._thread.start()

    def _run(self) -> None:
        while not self._stop.wait(self.tick_s):
            try:
                self.tick()
            except Exception:   # a display must never take the work down
                pass

    def close(self, success: bool = True) -> None:
        """Stop the display; after success print the stage-time table (if :attr:`summary`)."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
            self._thread = None
        with self._lock:
            if self._current is not None:
                self._finish(self._current)
                self._current = None
            if self._rich is not None:
                self._rich.stop()
                self._rich = None
            if success and self.summary and self._rows and self.elapsed() >= self.summary_min_s:
                self._print(self.table())

    # ---------------------------------------------------------------- reports
    def begin(self, stage: str) -> None:
        """A new stage starts (the previous one, if any, ends)."""
        with self._lock:
            if not self._started:
                self.start()
            if self._current is not None:
                self._finish(self._current)
            row = _Row(stage, self.clock())
            self._current = row
            self._rows.append(row)
            if self._rich is not None:
                row.task = self._rich.add_task(stage, total=None)
            self._emit(force=True)

    def end(self, stage: str) -> None:
        """``stage`` ended."""
        with self._lock:
            if self._current is not None and self._current.name == stage:
                self._finish(self._current)
                self._current = None

    def __call__(self, stage: str, done: int, total: int) -> None:
        """Progress of the current stage (or of an unannounced one, which starts it)."""
        with self._lock:
            if self._current is None:
                self.begin(self.default_stage or stage)
            row = self._current
            assert row is not None
            row.label, row.done, row.total = stage, int(done), int(total)
            self._update_rich(row)
            self._emit()

    def watch(self, name: str, poll: PollFn) -> None:
        """Show the worker job ``name``; ``poll()`` gives its latest progress."""
        with self._lock:
            if not self._started:
                self.start()
            row = _Row(name, self.clock(), in_worker=True, poll=poll)
            self._jobs[name] = row
            self._rows.append(row)
            if self._rich is not None:
                row.task = self._rich.add_task(f"{name} (worker)", total=None)
            self._emit(force=True)

    def unwatch(self, name: str, seconds: float | None = None) -> None:
        """The worker job ``name`` finished (its result was taken); ``seconds``: the time
        of its own work in the worker (default: since :meth:`watch`)."""
        with self._lock:
            row = self._jobs.pop(name, None)
            if row is not None:
                self._poll(row)
                self._finish(row)
                if seconds is not None:
                    row.ended = row.started + seconds

    # ---------------------------------------------------------------- drawing
    def tick(self) -> None:
        """Poll the worker jobs and redraw: in plain mode, print a line when the status
        changed (at most every :attr:`min_interval_s`) or :attr:`heartbeat_s` passed."""
        with self._lock:
            for row in self._jobs.values():
                self._poll(row)
                self._update_rich(row)
            self._emit()

    def elapsed(self) -> float:
        """Seconds since the display started."""
        return self.clock() - self._t0

    def status(self) -> str:
        """The current status line without the time stamp: the stage of this process, then
        the jobs in workers (those that report a count first, with it)."""
        parts = [self._current.status()] if self._current is not None else []
        counting = [row for row in self._jobs.values() if row.total]
        waiting = [row.name for row in self._jobs.values() if not row.total]
        parts += [row.status() for row in counting]
        if waiting:
            parts.append(f"in workers: {', '.join(waiting)}")
        return " | ".join(parts)

    def table(self) -> str:
        """The stage-time table: every stage and worker job with its wall time (s)."""
        width = max([len("total (wall)")] + [len(r.name) + (9 if r.in_worker else 0) for r in self._rows])
        lines = [f"{'stage':<{width}}  {'time (s)':>9}"]
        for r in self._rows:
            name = f"{r.name} (worker)" if r.in_worker else r.name
            seconds = (r.ended if r.ended is not None else self.clock()) - r.started
            lines.append(f"{name:<{width}}  {seconds:9.2f}")
        lines.append(f"{'total (wall)':<{width}}  {self.elapsed():9.2f}")
        return "\n".join(lines)

    def _poll(self, row: _Row) -> None:
        if row.poll is None:
            return
        got = row.poll()
        if got is not None:
            row.label, row.done, row.total = got[0], int(got[1]), int(got[2])

    def _finish(self, row: _Row) -> None:
        row.ended = self.clock()
        if self._rich is not None and row.task is not None:
            total = row.total or 1
            self._rich.update(row.task, total=total, completed=total)
            self._rich.stop_task(row.task)

    def _update_rich(self, row: _Row) -> None:
        if self._rich is None or row.task is None:
            return
        desc = row.name + (" (worker)" if row.in_worker else "")
        if row.label and row.label != row.name:
            desc += f": {row.label}"
        self._rich.update(row.task, description=desc, total=row.total or None, completed=row.done)

    def _emit(self, force: bool = False) -> None:
        if self.live:
            return   # rich redraws on its own thread
        status = self.status()
        if not status:
            return
        now = self.clock()
        since = now - self._last_line
        if force or since >= self.heartbeat_s or (status != self._last_status and since >= self.min_interval_s):
            self._last_line = now
            self._last_status = status
            self._print(f"[{now - self._t0:7.1f} s] {status}")

    def _print(self, text: str) -> None:
        assert self.stream is not None
        try:
            # one write with its newline: print() writes the text and the newline separately, and
            # an interrupt between the two would glue the next line ("interrupted") to this one
            self.stream.write(text + "\n")
            self.stream.flush()
        except (OSError, ValueError):   # a closed pipe must not fail the work
            pass
