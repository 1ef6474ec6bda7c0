"""Worker processes: the one pool of the build and of the studies.

A build's stages mostly wait on each other, but three jobs need only early results: the
interference and FCL checks (design and contact), the drawings (design and contact) and
the plots (the load and rating results). On a machine with two or more cores they run in
worker processes while the main process meshes and writes the rest; the main process takes
each result at the point of the run where a serial build computes it, so the report and
every file are the same as in a serial run (the golden test checks both ways). The tolerance
study and the design sweep run their chunks in the same kind of pool
(:func:`prs_geom.runtime.scaleout.run_chunks`).

Processes, not threads: FCL, manifold3d and matplotlib hold the GIL. A build's workers are
processes of its own (:func:`~prs_geom.runtime.sidecar.shared_pool`, ``processes``):
two interpreters and no resource tracker, kept for the next build and killed when one fails. The
studies' pool is joblib's *loky* executor, whose warm workers the rounds of a study reuse
(and a build that runs a tolerance study uses it too, so that the study shares the build's
workers). Both kinds are fresh interpreters (never forked: manifold3d and BLAS start
threads, and forking a process with threads can deadlock) that, unlike the standard
library's ``spawn``, do **not** re-run the caller's ``__main__`` module. A plain script
without an ``if __name__ == "__main__":`` guard, a Jupyter notebook, pytest and the
command line all work the same (docs/api.md, "Worker processes").

Every worker

* hands SIGINT and SIGTERM to the main process and otherwise ignores them, so that
  whichever process a Ctrl-C reaches (the main one, a worker, the whole process group),
  the main process stops the build and prints one line, and no worker prints a traceback;
* watches its parent and exits when the parent is gone (a main process killed with
  SIGKILL, as the out-of-memory killer does, leaves no worker running or writing).

When the work fails or is interrupted, the pool is shut down with its workers killed, not
waited for. Errors raised in a worker are re-raised by :meth:`Job.result` in the main
process, with their type.

A job may report progress: it is handed a :class:`FileProgress` that writes its latest
``(stage, done, total)`` to a small file which the main process polls
(:meth:`Job.poll`); a file, not a queue, because a queue shared with a loky worker needs a
manager process of its own, which could be orphaned too.

``PRS_GEOM_WORKERS`` sets the number of worker processes of a build (``0``: everything in
the main process, in order); the default is 2 on a machine with at least two cores, else 0.

Every process of a build (the main process, the workers, a rebuild's plot process) runs
BLAS and OpenMP on :data:`BUILD_THREADS` thread, unless the user set their thread counts
(:data:`THREAD_ENV`), so that

* the numbers do not depend on the machine: OpenBLAS's results depend on its thread count
  (a 300 x 300 matrix product and a dot product of 10^6 terms differ in the last bits
  between 1 and 2 threads, measured), and a build on 2 cores or on 64, serial or with
  workers, gives the same bytes;
* the processes do not oversubscribe the cores: OpenBLAS starts a thread per core in every
  process, which spin between calls on cores the other processes need (0.8 s of the
  default build's 13 s of CPU and 0.4 s of its wall time, six alternating runs on two cores).
"""
from __future__ import annotations

import os
import shutil
import signal
import tempfile
import threading
import time
from pathlib import Path
from typing import Any, Callable

from prs_geom.model.io import write_file_atomic
from prs_geom.runtime.memwatch import release_free_heap

__all__ = ["WORKERS_ENV", "THREAD_ENV", "BUILD_THREADS", "default_workers", "user_threads", "thread_overrides", "thread_env", "build_threads", "Job", "Background", "FileProgress", "PoolClosed", "worker_init",
           "signals_ignored"]

#: Environment variable: number of worker processes of a build (0 = serial).
WORKERS_ENV = "PRS_GEOM_WORKERS"
#: Environment variables that set the threads of BLAS and OpenMP in a process, read when the
#: library loads (before numpy's import in a worker).
THREAD_ENV = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
#: BLAS and OpenMP threads in every process of a build (module doc).
BUILD_THREADS = 1
#: Seconds between two looks of a worker at its parent process.
PARENT_WATCH_S = 0.5
#: Seconds an idle worker of the pool waits for more work before it exits.
IDLE_S = 30


class PoolClosed(RuntimeError):
    """A job was given to a pool of :class:`Background` ``processes`` that is closed (a
    :class:`~prs_geom.runtime.sidecar.SidecarPool` idle too long closes itself)."""


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


def user_threads() -> tuple[str, ...]:
    """The user's settings of :data:`THREAD_ENV` ('' where unset): a build leaves the
    thread counts alone when any is set."""
    return tuple(os.environ.get(name, "").strip() for name in THREAD_ENV)


def thread_overrides() -> dict[str, str]:
    """The variables a new worker process gets on top of this one's environment: BLAS and
    OpenMP on :data:`BUILD_THREADS` thread, none when the user set their thread counts."""
    return {} if any(user_threads()) else {name: str(BUILD_THREADS) for name in THREAD_ENV}


def thread_env() -> dict[str, str]:
    """The environment of a new worker process: this one's with :func:`thread_overrides`."""
    return {**os.environ, **thread_overrides()}


def build_threads() -> Any:
    """A context in which this process's BLAS and OpenMP run :data:`BUILD_THREADS` thread
    (threadpoolctl: they are loaded already, so an environment variable would come too
    late); no limit when the user set the thread counts."""
    import contextlib

    if any(user_threads()):
        return contextlib.nullcontext()
    from threadpoolctl import threadpool_limits

    return threadpool_limits(limits=BUILD_THREADS)


# --------------------------------------------------------------------------- in the worker
def _forward_to_parent(parent: int) -> Callable[[int, Any], None]:
    def handler(signum: int, frame: Any) -> None:
        # the main process decides: it stops the build and kills every worker, this one too
        try:
            os.kill(parent, signum)
        except OSError:
            os._exit(128 + signum)
    return handler


def _watch_parent(parent: int) -> None:
    while True:
        time.sleep(PARENT_WATCH_S)
        if os.getppid() != parent:
            # orphaned: the main process died without stopping us; leave at once, writing nothing
            os._exit(1)


#: The signals a worker hands to the main process.
_FORWARDED = (signal.SIGINT, signal.SIGTERM)


def worker_init(parent: int) -> None:
    """Initialiser of every worker process (module doc): forward SIGINT and SIGTERM to the
    main process ``parent`` and exit when it is gone.

    The worker was started with both signals blocked (:func:`_blocked`), so that one that
    arrives while the new interpreter is still importing waits until the handler is in
    place instead of printing a traceback from the middle of the start-up."""
    handler = _forward_to_parent(parent)
    for sig in _FORWARDED:
        signal.signal(sig, handler)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _FORWARDED)
    threading.Thread(target=_watch_parent, args=(parent,), name="prs-geom-parent-watch", daemon=True).start()


def _start_resource_trackers() -> None:
    from multiprocessing import resource_tracker as stdlib_tracker

    from joblib.externals.loky.backend import resource_tracker as loky_tracker

    stdlib_tracker.ensure_running()
    loky_tracker.ensure_running()


class _blocked:
    """SIGINT and SIGTERM blocked in this thread while the pool starts processes (or the
    thread that starts them later): the children inherit the blocked mask through the
    fork and exec, until :func:`worker_init` installs their handlers. A signal sent to the
    main process meanwhile stays pending and is delivered when the block is lifted."""

    def __enter__(self) -> None:
        self._old = signal.pthread_sigmask(signal.SIG_BLOCK, _FORWARDED)

    def __exit__(self, *exc: object) -> None:
        signal.pthread_sigmask(signal.SIG_SETMASK, self._old)


def make_executor(workers: int) -> Any:
    """The loky pool of ``workers`` processes with :func:`worker_init` in each.

    loky's *reusable* executor: the build and the studies that follow it (or a tolerance
    synthesis that runs many Monte Carlo rounds) share warm workers instead of starting
    new interpreters each time; idle workers leave after :data:`IDLE_S` seconds. The
    workers start with BLAS and OpenMP on one thread (:func:`thread_overrides`)."""
    from joblib.externals.loky import get_reusable_executor

    return get_reusable_executor(max_workers=workers, timeout=IDLE_S, initializer=worker_init,
                                 initargs=(os.getpid(),), env=thread_overrides())


class FileProgress:
    """A picklable progress callback for a worker: writes ``stage done total`` to ``path``
    (atomically, at most every ``interval`` seconds and always at completion)."""

    def __init__(self, path: str, interval: float = 0.25) -> None:
        self.path = path
        self.interval = interval
        self._last = 0.0

    def __getstate__(self) -> dict[str, Any]:
        return {"path": self.path, "interval": self.interval}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__init__(state["path"], state["interval"])

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if done < total and now - self._last < self.interval:
            return
        self._last = now
        try:
            write_file_atomic(Path(self.path), f"{done}\t{total}\t{stage}")
        except OSError:   # progress is a courtesy: never fail the job for it
            pass


def _timed(fn: Callable[..., Any], args: tuple, kwargs: dict) -> tuple[Any, float]:
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    release_free_heap()     # the job's temporaries, before the worker's next job
    return out, time.perf_counter() - t0


# --------------------------------------------------------------------------- in the main process
class Job:
    """One piece of background work: :meth:`result` waits for it (or re-raises its error).
    Without workers the job runs when its result is first asked for, so a serial build does
    its work in the order the stages take it, as before there were workers."""

    def __init__(self, future: Any = None, call: tuple | None = None, progress_file: str | None = None) -> None:
        self._future = future
        self._call = call
        self._progress_file = progress_file
        self._value: Any = None
        self._seconds = 0.0
        #: whether the job runs (or ran) in a worker process
        self.in_worker = future is not None

    def running(self) -> bool:
        """Whether the job is still at work in its worker."""
        return self._future is not None and not self._future.done()

    def poll(self) -> tuple[str, int, int] | None:
        """The job's latest progress ``(stage, done, total)`` from its worker, or None."""
        if self._progress_file is None:
            return None
        try:
            with open(self._progress_file, encoding="utf-8") as fh:
                done, total, stage = fh.read().split("\t", 2)
            return stage, int(done), int(total)
        except (OSError, ValueError):
            return None

    def result(self) -> Any:
        """The job's return value (waits for it; a job without a worker runs now, once). An
        error raised by the job is raised here, with its type."""
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
    """A pool of ``workers`` processes (none: each job runs when its result is taken): loky's
    shared pool, or the one that ``processes(workers)`` gives (the build's:
    :func:`~prs_geom.runtime.sidecar.shared_pool`; anything with ``submit(fn, args, kwargs)``
    giving futures of ``(value, seconds)`` or raising :class:`PoolClosed`, ``usable``,
    ``reusable`` and ``close()``).

    Use as a context manager: leaving it normally leaves reusable workers (loky's, the
    build's shared pool) idle for the next user and closes others; leaving it with an
    exception (an error, Ctrl-C, SIGTERM) kills the workers at once. Take
    every job's result before leaving normally. Job functions and their arguments must be picklable (module-level
    functions, frozen dataclasses, numpy arrays).
    """

    def __init__(self, workers: int | None = None, sidecar: Any = None,
                 processes: Callable[[int], Any] | None = None) -> None:
        self.workers = default_workers() if workers is None else workers
        #: the build's plot process (:class:`prs_geom.runtime.sidecar.Sidecar`), or None
        self.sidecar = sidecar
        #: gives a pool of its own for the worker count (the build's:
        #: :func:`prs_geom.runtime.sidecar.shared_pool`; taken at the first job, closed on
        #: leaving unless reusable), or None: loky's shared pool
        self.processes = processes
        self._pool: Any = None
        self._progress_dir: str | None = None
        self._jobs = 0

    def __enter__(self) -> "Background":
        self._first = _FirstSignalOnly()
        self._first.install()
        return self

    def __exit__(self, exc_type: Any, *exc: object) -> None:
        try:
            self.close(kill=exc_type is not None)
        finally:
            self._first.restore()

    def submit(self, fn: Callable[..., Any], *args: Any, report_progress: bool = False, plot: bool = False,
               **kwargs: Any) -> Job:
        """Run ``fn(*args, **kwargs)`` in a worker (or later, in this process, without workers).

        ``report_progress=True`` passes ``progress=`` a :class:`FileProgress` to the function
        in a worker, read back with :meth:`Job.poll`; without workers the caller passes its
        own callback in ``kwargs``. ``plot=True``: a figure, drawn by the pool's
        :attr:`sidecar` when it has one."""
        if plot and self.sidecar is not None:
            return Job(self.sidecar.submit(fn, args, kwargs))
        if self.workers <= 0:
            return Job(call=(fn, args, kwargs))
        progress_file = None
        if report_progress:
            if self._progress_dir is None:
                _clean_stale_progress_dirs()
                self._progress_dir = tempfile.mkdtemp(prefix=f"{_PROGRESS_PREFIX}{os.getpid()}-")
            self._jobs += 1
            progress_file = os.path.join(self._progress_dir, f"job{self._jobs}")
            kwargs = {**kwargs, "progress": FileProgress(progress_file)}
        if self.processes is not None:
            self.start()
            try:
                future = self._pool.submit(fn, args, kwargs)
            except PoolClosed:      # idle too long since the last job: a new pool
                self._pool = self.processes(self.workers)
                future = self._pool.submit(fn, args, kwargs)
            return Job(future, progress_file=progress_file)
        # the pool starts its workers (and its manager thread, which starts any later ones)
        # on submit: with the signals blocked, so that the children start with them blocked.
        # The resource trackers first: the standard library's unblocks both signals after
        # starting its own process, which would undo the block for the workers after it.
        _start_resource_trackers()
        with _blocked():
            if self._pool is None:
                self._pool = make_executor(self.workers)
            future = self._pool.submit(_timed, fn, args, kwargs)
        return Job(future, progress_file=progress_file)

    def start(self) -> None:
        """Take a pool of its own (:attr:`processes`) now; nothing when there is none, no
        worker, or the one it has is usable."""
        if self.processes is not None and self.workers > 0 and (self._pool is None or not self._pool.usable):
            self._pool = self.processes(self.workers)

    def close(self, kill: bool = False) -> None:
        """Done with the pool: leave its idle workers for the next user (they exit after
        :data:`IDLE_S` s), or with ``kill`` kill them (SIGKILL) and reap them.

        While killing, SIGINT and SIGTERM are ignored in the main thread: after a Ctrl-C to
        the process group each worker hands its copy to this process, and a second
        KeyboardInterrupt raised in the middle of the clean-up would cut it short."""
        pool, self._pool = self._pool, None
        sidecar, self.sidecar = self.sidecar, None
        with signals_ignored(kill):
            if sidecar is not None:
                sidecar.close()
            if pool is not None and self.processes is not None:
                if kill or not pool.reusable:
                    pool.close()
            elif pool is not None and kill:
                _kill_pool(pool)
            if self._progress_dir is not None:
                shutil.rmtree(self._progress_dir, ignore_errors=True)
                self._progress_dir = None


_PROGRESS_PREFIX = "prs-geom-progress-"


def _clean_stale_progress_dirs() -> None:
    """Remove the progress folders of dead processes (one killed with SIGKILL cannot)."""
    root = tempfile.gettempdir()
    try:
        names = os.listdir(root)
    except OSError:
        return
    for name in names:
        if not name.startswith(_PROGRESS_PREFIX):
            continue
        pid = name[len(_PROGRESS_PREFIX):].split("-", 1)[0]
        if pid.isdigit() and not _alive(int(pid)):
            shutil.rmtree(os.path.join(root, name), ignore_errors=True)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:   # exists, another user's
        return True
    return True


class _FirstSignalOnly:
    """While a :class:`Background` block runs (main thread only): the first SIGINT or SIGTERM
    goes to the handler that was there before (Python's KeyboardInterrupt, the CLI's
    handler), and every one after it is ignored until the block has cleaned up.

    A Ctrl-C to the process group reaches this process once directly and once more from each
    worker that hands its copy on (module doc); those copies can land while the first
    KeyboardInterrupt is still unwinding towards :meth:`Background.__exit__`, before
    :meth:`Background.close` ignores signals, and would cut the clean-up short with a second
    traceback."""

    def __init__(self) -> None:
        self.active = threading.current_thread() is threading.main_thread()
        self._previous: dict[int, Any] = {}

    def install(self) -> None:
        if not self.active:
            return
        for sig in _FORWARDED:
            self._previous[sig] = signal.signal(sig, self._handle)

    def _handle(self, sig: int, frame: Any) -> None:
        for other in self._previous:
            signal.signal(other, signal.SIG_IGN)
        previous = self._previous.get(sig)
        if callable(previous):
            previous(sig, frame)
        elif previous == signal.SIG_DFL:
            # the default action (end the process): restore it and take the signal again
            signal.signal(sig, signal.SIG_DFL)
            os.kill(os.getpid(), sig)

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)
        self._previous = {}


class signals_ignored:
    """SIGINT and SIGTERM ignored while the block runs (main thread only; elsewhere, or
    with ``active`` false, nothing changes)."""

    def __init__(self, active: bool) -> None:
        self.active = active and threading.current_thread() is threading.main_thread()
        self._previous: dict[int, Any] = {}

    def __enter__(self) -> None:
        if self.active:
            for sig in _FORWARDED:
                self._previous[sig] = signal.signal(sig, signal.SIG_IGN)

    def __exit__(self, *exc: object) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def _kill_pool(pool: Any) -> None:
    """Kill the pool's workers now and wait (briefly) until the OS has reaped them, so that
    no worker still writes into a folder the caller is about to remove.

    loky's own shutdown with ``kill_workers`` goes first, so that its manager thread sees an
    orderly shutdown rather than workers dying under it (which can make that thread fail
    with a traceback on the console); any process left is then killed here. An exception
    of that thread during the kill is not the user's business and is not printed."""
    processes = list(getattr(pool, "_processes", {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    previous_hook = threading.excepthook

    def quiet_manager(args: Any) -> None:
        if args.thread is not manager:
            previous_hook(args)

    threading.excepthook = quiet_manager
    try:
        pool.shutdown(wait=False, kill_workers=True)
        deadline = time.monotonic() + 5.0
        if manager is not None:
            manager.join(max(0.0, deadline - time.monotonic()))
        for p in processes:
            try:
                if p.is_alive():
                    p.kill()
                p.join(max(0.0, deadline - time.monotonic()))
            except (OSError, AttributeError, ValueError, AssertionError):
                pass
    finally:
        threading.excepthook = previous_hook
