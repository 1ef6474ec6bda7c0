"""Work a build runs beside its main line, in worker processes.

A build's stages mostly wait on each other, but three jobs need only early results: the
interference and FCL checks (design and contact), the drawings (design and contact) and
the plots (the load and rating results). On a machine with two or more cores they run in
worker processes while the main process meshes and writes the rest; the main process takes
each result at the point of the run where the stage used to be, so the report and every
file are the same as in a serial run (the golden test checks both ways).

Processes, not threads: FCL, manifold3d and matplotlib hold the GIL. The workers are
*spawned* (a fresh interpreter importing only what its job needs), never forked: manifold3d
and BLAS start threads, and forking a process with threads can deadlock. Errors raised in a
worker are re-raised by :meth:`Job.result` in the main process, with their type.

``PRS_GEOM_WORKERS`` sets the number of worker processes (``0``: everything in the main
process, in order); the default is 2 on a machine with at least two cores, else 0.
"""
from __future__ import annotations

import os
import time
from concurrent.futures import Future, ProcessPoolExecutor
from typing import Any, Callable

#: Environment variable: number of worker processes of a build (0 = serial).
WORKERS_ENV = "PRS_GEOM_WORKERS"


def default_workers() -> int:
    """Worker processes for a build: ``$PRS_GEOM_WORKERS``, else 2 with two or more cores."""
    text = os.environ.get(WORKERS_ENV, "").strip()
    if text:
        from prs_geom.model.errors import DesignError

        # an input error like a bad flag (exit code 2), named after the variable
        if not text.isdigit():
            raise DesignError(WORKERS_ENV, text, "must be a whole number >= 0 (0: no worker processes)")
        return int(text)
    return 2 if (os.cpu_count() or 1) >= 2 else 0


def _timed(fn: Callable[..., Any], args: tuple, kwargs: dict) -> tuple[Any, float]:
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


class Job:
    """One piece of background work: :meth:`result` waits for it (or re-raises its error).
    Without workers the job runs when its result is first asked for, so a serial build does
    its work in the order the stages take it, as before there were workers."""

    def __init__(self, future: Future | None = None, call: tuple | None = None) -> None:
        self._future = future
        self._call = call
        self._value: Any = None
        self._seconds = 0.0

    def result(self) -> Any:
        if self._future is not None:
            self._value, self._seconds = self._future.result()
            self._future = None
        elif self._call is not None:
            fn, args, kwargs = self._call
            self._call = None
            self._value, self._seconds = _timed(fn, args, kwargs)
        return self._value

    @property
    def seconds(self) -> float:
        """Time the job itself took (s), in its worker; valid after :meth:`result`."""
        self.result()
        return self._seconds


class Background:
    """A pool of ``workers`` spawned processes (none: each job runs when its result is taken).

    Use as a context manager; leaving it waits for the jobs still running and stops the
    workers. Job functions and their arguments must be picklable (module-level functions,
    frozen dataclasses, numpy arrays).
    """

    def __init__(self, workers: int | None = None) -> None:
        self.workers = default_workers() if workers is None else workers
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> "Background":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> Job:
        if self.workers <= 0:
            return Job(call=(fn, args, kwargs))
        if self._pool is None:
            import multiprocessing

            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"))
        return Job(self._pool.submit(_timed, fn, args, kwargs))

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
