"""A runtime memory guard: stop a job cleanly before its resident memory passes the budget.

The up-front estimate (:mod:`prs_geom.mesh.budget`) refuses a job that would not fit; this
watch holds the budget while the job runs, for what an estimate cannot foresee. A daemon
thread samples, every :data:`SAMPLE_S` seconds, the resident set size of this process and
of every process below it (the worker pool, the resource trackers) from ``/proc``; when
their sum passes the budget it

1. marks the watch as breached and raises :class:`ResourceLimitError` in the main thread
   (through a SIGUSR1 handler and ``_thread.interrupt_main``), so that the job unwinds
   like an interrupt: workers killed, temporary output removed, nothing written, exit 3;
2. if the main thread is inside a long library call and does not unwind within
   :data:`GRACE_S` seconds, kills the child processes (SIGKILL), whose memory is then freed
   at once; the main thread meets their death (a broken pool) when it returns, and the
   caller turns that into the same :class:`ResourceLimitError` (:attr:`MemoryWatch.breached`).

What the calling process already held beyond the interpreter share of the estimate
(``base_bytes``: :data:`prs_geom.mesh.budget.BASE_BYTES` for a build) when the job started, a notebook's earlier work
say, is not the job's: the limit rises by it (:attr:`MemoryWatch.carried`). In a fresh
command-line process there is none.

Linux only (``/proc``); elsewhere the watch does nothing. It imports nothing of prs_geom but
the model's error type and byte formatting (:class:`~prs_geom.model.errors.ResourceLimitError`).
"""
from __future__ import annotations

import os
import signal
import threading
import time
from typing import Any

from prs_geom.model.errors import ResourceLimitError, format_bytes

__all__ = ["MemoryWatch", "process_tree_rss", "release_free_heap", "SAMPLE_S", "GRACE_S"]

#: Seconds between two samples of the resident memory.
SAMPLE_S = 0.05
#: Seconds the main thread has to unwind after a breach before the children are killed.
GRACE_S = 1.0
_PAGE = os.sysconf("SC_PAGE_SIZE") if hasattr(os, "sysconf") else 4096
_MALLOC_TRIM: Any = None


def release_free_heap() -> None:
    """Give the C heap's free pages back to the system (glibc's ``malloc_trim``).

    glibc keeps the memory that a stage's large temporaries freed (meshes, BVHs, a PDF's
    figures) in its heap, where it still counts as resident: measured on the default build,
    the main process held 172 MB after the meshes stage and 112 MB once trimmed. Called
    after each stage, each worker job and the meshes stage's large steps, so that the
    build's processes hold what they use, not what they once used: the default build's
    peak (process tree, six alternating runs) is 548-576 MB with it, 587-624 MB without. It
    costs about 0.1 ms a call. A no-op where the C library is not glibc.
    """
    global _MALLOC_TRIM
    if _MALLOC_TRIM is None:
        try:
            import ctypes

            _MALLOC_TRIM = ctypes.CDLL("libc.so.6").malloc_trim
        except (OSError, AttributeError):
            _MALLOC_TRIM = False
    if _MALLOC_TRIM:
        _MALLOC_TRIM(0)


def _rss(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/statm", "rb") as fh:
            return int(fh.read().split()[1]) * _PAGE
    except (OSError, ValueError, IndexError):
        return 0


def _children(pid: int) -> list[int]:
    out: list[int] = []
    try:
        tasks = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return out
    for tid in tasks:
        try:
            with open(f"/proc/{pid}/task/{tid}/children", "rb") as fh:
                out += [int(x) for x in fh.read().split()]
        except (OSError, ValueError):
            pass
    return out


def _descendants(pid: int) -> list[int]:
    out, todo = [], _children(pid)
    while todo:
        child = todo.pop()
        out.append(child)
        todo += _children(child)
    return out


def process_tree_rss(pid: int | None = None) -> tuple[int, list[int]]:
    """(resident bytes of ``pid`` (default this process) and all its descendants, the
    descendants' pids)."""
    pid = os.getpid() if pid is None else pid
    kids = _descendants(pid)
    return _rss(pid) + sum(_rss(k) for k in kids), kids


class MemoryWatch:
    """Context manager: the guard of the module docstring for ``budget`` bytes.

    Attributes
    ----------
    breached : bool
        True once the budget was passed (the job must then end with
        :class:`ResourceLimitError`, whatever exception it unwound with).
    peak : int
        The largest sum seen, bytes.
    """

    def __init__(self, budget: int, what: str = "this job", *, base_bytes: int = 0) -> None:
        self.budget = int(budget)
        self.what = what
        #: the interpreter share (bytes) the job's up-front estimate already counts
        #: (:data:`prs_geom.mesh.budget.BASE_BYTES` for a build)
        self.base_bytes = int(base_bytes)
        #: what the calling process held before the job beyond the interpreter share the
        #: estimate counts (a notebook or test process with earlier work in memory): not the
        #: job's, so the limit rises by it
        self.carried = 0
        self.breached = False
        self.peak = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._previous: Any = None
        self._main = threading.current_thread() is threading.main_thread()

    def error(self) -> ResourceLimitError:
        """The error a breached job ends with."""
        return ResourceLimitError(
            f"{self.what} was stopped: its resident memory reached {format_bytes(self.peak)}, over the budget "
            f"{format_bytes(self.budget)} (the estimate up front was lower than what it used). Nothing was "
            f"written. Raise --memory-budget, or coarsen mesh.chord_tolerance_mm")

    def __enter__(self) -> "MemoryWatch":
        if not os.path.exists("/proc/self/statm"):
            return self
        self.carried = max(0, process_tree_rss()[0] - self.base_bytes)
        if self._main:
            self._previous = signal.signal(signal.SIGUSR1, self._on_breach)
        self._thread = threading.Thread(target=self._run, name="prs-geom-memory-watch", daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        if self._thread is not None:
            self._thread.join(2.0)
        if self._main and self._previous is not None:
            signal.signal(signal.SIGUSR1, self._previous)

    def _on_breach(self, signum: int, frame: Any) -> None:
        raise self.error()

    def _run(self) -> None:
        import _thread

        breached_at = None
        while not self._stop.wait(SAMPLE_S):
            total, kids = process_tree_rss()
            self.peak = max(self.peak, total)
            if not self.breached and total > self.budget + self.carried:
                self.breached = True
                breached_at = time.monotonic()
                if self._main:
                    _thread.interrupt_main(signal.SIGUSR1)
            if self.breached and breached_at is not None and time.monotonic() - breached_at > GRACE_S:
                for k in kids:
                    try:
                        os.kill(k, signal.SIGKILL)
                    except OSError:
                        pass
                breached_at = None
