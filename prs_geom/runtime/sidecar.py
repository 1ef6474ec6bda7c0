"""Worker processes spoken to over pipes: the plot process of a rebuild (:class:`Sidecar`)
and the worker processes of a build (:class:`SidecarPool`).

**The build's pool.** A cold build hands its checks, drawings, mesh checks and plots to two
worker processes (:mod:`.pool`). Each is a :class:`Sidecar`; a thread of the main process
sends the next queued job to whichever process is idle and reads the results as they come,
so the jobs spread over the processes as in a pool. It costs two interpreters and nothing
else. loky's pool, which the studies keep (their rounds reuse warm workers), also starts two
resource trackers, one of which imports joblib and numpy (32 MB between them at the default
build's peak), and imports joblib in each worker (6 MB each): measured on the default build,
six alternating runs each, the process tree peaks at 545-562 MB on this pool and 583-602 MB
on loky's. The processes start at the build's first job and, like loky's, stay for the
next build of the same interpreter (a script, a notebook, a test session), which finds their
imports done (:func:`shared_pool`, :class:`~prs_geom.runtime.pool.Background`
``processes``); they go after :data:`SHARED_IDLE_S` s without a job, when a build fails or
is interrupted (killed), and when the interpreter exits.

**The plot process of a rebuild**: one worker, started before the stage records are read.

A rebuild that restores the meshes, the checks and the drawings from the stage cache
(:mod:`prs_geom.build_cache`) has no work left for a pool of workers (:mod:`.pool`) but the
figures of the stages whose inputs changed: after a new ``loading.axial_load_n``, the three
load figures and the rating figure. Drawn in the main process they cost about as much as the
rest of the rebuild together: matplotlib's import (0.3 s) and four figures in PNG and SVG
(0.5 s). Started while the main process reads the records, one process imports matplotlib
and warms its fonts meanwhile, and draws the figures while the main process restores the
other stages' files; a loky pool would start three interpreters for it (two resource
trackers and the worker) and import joblib in each.

The process runs ``python -m prs_geom.runtime.sidecar PARENT_PID [MODULE:WARM_UP]``: a fresh
interpreter, not a fork (see :mod:`.pool`). It takes the same care as a pool worker
(:func:`~prs_geom.runtime.pool.worker_init`): started with SIGINT and SIGTERM blocked, it
hands both to the main process; it leaves when the main process is gone (its pipe closes, or
its parent changes). Jobs go in and results come back over its standard input and output,
in order, as length-prefixed pickles, so a job function and its arguments must pickle as for
a pool worker; an error raised by a job is raised by :meth:`Sidecar.result`, with its type.
Whatever else the process prints goes to its standard error.

Only the build uses these processes, and only when ``$PRS_GEOM_WORKERS`` allows worker
processes: a rebuild's plot process for the plots only
(:meth:`prs_geom.pipeline.BuildContext.add_plot`), whose files are the same bytes wherever
they are drawn (``tests/test_build_cache.py``); the pool for every job of a cold build.
"""
from __future__ import annotations

import atexit
import os
import pickle
import select
import subprocess
import sys
import threading
from collections import deque
from typing import Any, BinaryIO, Callable

__all__ = ["Sidecar", "SidecarPool", "shared_pool", "main"]

#: Bytes of the length prefix of each message.
_HEADER = 8


def _send(stream: BinaryIO, obj: Any) -> None:
    _send_bytes(stream, pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def _send_bytes(stream: BinaryIO, data: bytes) -> None:
    for part in (len(data).to_bytes(_HEADER, "little"), data):
        view = memoryview(part)
        while view:     # an unbuffered pipe may take part of a large write
            view = view[stream.write(view) or 0:]
    stream.flush()


def _read_exact(stream: BinaryIO, size: int) -> bytes:
    """``size`` bytes, or raise EOFError when the other side closed its end first (an
    unbuffered pipe returns what it has)."""
    chunks = []
    while size:
        chunk = stream.read(size)
        if not chunk:
            raise EOFError
        chunks.append(chunk)
        size -= len(chunk)
    return b"".join(chunks)


def _receive_bytes(stream: BinaryIO) -> bytes:
    """The next message's pickle (EOFError: the other side closed its end)."""
    return _read_exact(stream, int.from_bytes(_read_exact(stream, _HEADER), "little"))


def _receive(stream: BinaryIO) -> Any:
    return pickle.loads(_receive_bytes(stream))


class _Future:
    """The result of the ``index``-th job of a sidecar (the interface of
    :class:`concurrent.futures.Future` that :class:`~prs_geom.runtime.pool.Job` uses)."""

    def __init__(self, sidecar: "Sidecar", index: int) -> None:
        self._sidecar = sidecar
        self._index = index

    def done(self) -> bool:
        return self._sidecar.finished(self._index)

    def result(self) -> Any:
        return self._sidecar.result(self._index)


class Sidecar:
    """One plot process (module docstring), started at construction. It runs BLAS and
    OpenMP on one thread, as every process of a build does
    (:func:`~prs_geom.runtime.pool.thread_env`).

    Parameters
    ----------
    warm : callable or None
        A module-level function the process calls with no arguments before it takes jobs
        (it is named to the process, not pickled): the build's is
        :func:`prs_geom.exports.plots.warm_up`, matplotlib imported and its fonts loaded.
    """

    def __init__(self, warm: Callable[[], None] | None = None) -> None:
        from prs_geom.runtime.pool import _blocked, thread_env

        argv = [sys.executable, "-m", "prs_geom.runtime.sidecar", str(os.getpid())]
        if warm is not None:
            argv.append(f"{warm.__module__}:{warm.__qualname__}")
        with _blocked():    # the child starts with SIGINT and SIGTERM blocked (pool._blocked)
            # unbuffered: what select() sees on the pipe is all there is (finished())
            self._proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0,
                                          env=thread_env())
        self._sent = 0
        self._received: list[tuple[bool, Any]] = []

    @property
    def pid(self) -> int:
        return self._proc.pid

    def submit(self, fn: Callable[..., Any], args: tuple, kwargs: dict) -> _Future:
        """Queue ``fn(*args, **kwargs)``; its future's result is ``(value, seconds)`` as
        :func:`prs_geom.runtime.pool._timed` gives it."""
        _send(self._proc.stdin, (fn, args, kwargs))
        self._sent += 1
        return _Future(self, self._sent - 1)

    def _take_one(self) -> None:
        try:
            self._received.append(_receive(self._proc.stdout))
        except EOFError:
            code = self._proc.wait()
            raise RuntimeError(f"the plot process of the build ended (exit code {code}) before its jobs were "
                               "done") from None

    def finished(self, index: int) -> bool:
        """Whether job ``index`` has finished (reads the results that have arrived)."""
        while len(self._received) <= index:
            ready, _, _ = select.select([self._proc.stdout], [], [], 0)
            if not ready:
                return False
            self._take_one()
        return True

    def result(self, index: int) -> Any:
        """``(value, seconds)`` of job ``index`` (waits for it); its error, raised."""
        while len(self._received) <= index:
            self._take_one()
        ok, value = self._received[index]
        if not ok:
            raise value
        return value

    def kill(self) -> None:
        """Stop the process (SIGKILL) and reap it, leaving its pipes open."""
        if self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()

    def close(self) -> None:
        """Stop the process (SIGKILL) and reap it; again, nothing. It holds nothing worth a clean exit: its
        files are written and its results taken, or the build failed; an orderly interpreter
        shutdown with matplotlib loaded would add 0.15 s to every rebuild."""
        if self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()
        for stream in (self._proc.stdin, self._proc.stdout):
            try:
                stream.close()
            except OSError:
                pass


class _PoolJob:
    """A job of a :class:`SidecarPool`: the interface of :class:`concurrent.futures.Future`
    that :class:`~prs_geom.runtime.pool.Job` uses."""

    def __init__(self, pool: "SidecarPool", request: bytes) -> None:
        self._pool = pool
        self.request = request
        self.finished = False
        self.reply: tuple[bool, Any] = (False, None)

    def done(self) -> bool:
        with self._pool.changed:
            return self.finished

    def result(self) -> Any:
        """``(value, seconds)`` (waits for it); the job's error, raised."""
        with self._pool.changed:
            self._pool.changed.wait_for(lambda: self.finished)
        ok, value = self.reply
        if not ok:
            raise value
        return value


class SidecarPool:
    """``workers`` :class:`Sidecar` processes sharing one queue of jobs (module doc).

    Jobs are pickled by :meth:`submit` (so a job that does not pickle fails there, in the
    caller) and sent, in order, each to the first process that is idle. A process that ends
    before its job is done fails that job and every job still queued with RuntimeError (a
    worker killed by the memory watch, say); the others keep their results. :meth:`close`
    kills the processes and reaps them.

    Parameters
    ----------
    workers : int
        Number of processes (at least 1).
    idle_s : float or None
        The pool closes itself after this many seconds without a job (the processes of
        :func:`shared_pool`, which later builds reuse); None: only :meth:`close` closes it.
    """

    def __init__(self, workers: int, idle_s: float | None = None) -> None:
        if workers < 1:
            raise ValueError(f"workers = {workers}: a pool needs at least one process")
        self.changed = threading.Condition()
        self._queue: deque[_PoolJob] = deque()
        self._running: dict[Sidecar, _PoolJob] = {}
        self._failure: RuntimeError | None = None
        self._closed = False
        self._closing = False
        self._idle_s = idle_s
        #: whether the pool outlives the caller's use of it (:func:`shared_pool`)
        self.reusable = idle_s is not None
        self._wake_r, self._wake_w = os.pipe()
        from prs_geom.runtime.pool import user_threads

        #: the user's thread settings the processes started with (shared_pool: a change of
        #: them between two builds starts new processes)
        self.user_threads = user_threads()
        self.processes = [Sidecar() for _ in range(workers)]
        self.workers = workers
        self._thread = threading.Thread(target=self._serve, name="prs-geom-pool", daemon=True)
        self._thread.start()

    @property
    def usable(self) -> bool:
        """Whether the pool takes jobs that can succeed: open and no process lost."""
        with self.changed:
            return not self._closed and self._failure is None

    def submit(self, fn: Callable[..., Any], args: tuple, kwargs: dict) -> _PoolJob:
        """Queue ``fn(*args, **kwargs)``. Raises :class:`~prs_geom.runtime.pool.PoolClosed`
        when the pool is closed."""
        job = _PoolJob(self, pickle.dumps((fn, args, kwargs), protocol=pickle.HIGHEST_PROTOCOL))
        with self.changed:
            if self._closed:
                from prs_geom.runtime.pool import PoolClosed

                raise PoolClosed("the worker processes of the build are closed")
            if self._failure is not None:
                self._finish(job, (False, self._failure))
                return job
            self._queue.append(job)
        os.write(self._wake_w, b"\0")
        return job

    def _finish(self, job: _PoolJob, reply: tuple[bool, Any]) -> None:
        """Hand ``job`` its reply (holding :attr:`changed`)."""
        job.finished, job.reply, job.request = True, reply, b""
        self.changed.notify_all()

    def _fail(self, failure: RuntimeError, sidecar: Sidecar) -> None:
        """``sidecar`` ended: its job, every queued job and every later one fail; the other
        processes finish theirs (holding :attr:`changed`)."""
        self._failure = failure
        self._finish(self._running.pop(sidecar), (False, failure))
        while self._queue:
            self._finish(self._queue.popleft(), (False, failure))

    def _serve(self) -> None:
        """The pool's thread: sends each queued job to the first idle process (outside the
        lock: a process still starting reads its job only then, and the caller must not wait
        for that) and finishes each job when its reply arrives."""
        while True:
            sends = []
            with self.changed:
                if self._closed:
                    return
                idle = not self._queue and not self._running
                for sidecar in self.processes:
                    if self._queue and sidecar not in self._running:
                        self._running[sidecar] = self._queue.popleft()
                        sends.append((sidecar, self._running[sidecar]))
                busy = {sidecar._proc.stdout: sidecar for sidecar in self._running}
            for sidecar, job in sends:
                try:
                    _send_bytes(sidecar._proc.stdin, job.request)
                except OSError:     # the process is gone: its reply stream says so
                    pass
                job.request = b""   # the pickle (a mesh check's parts: tens of MB) is the process's now
            del sends
            ready, _, _ = select.select([self._wake_r, *busy], [], [], self._idle_s if idle else None)
            if not ready:
                with self.changed:      # nothing came in idle_s seconds: close, unless a job just did
                    if self._queue or self._running:
                        continue
                self.close()
                return
            for stream in ready:
                if stream == self._wake_r:
                    os.read(self._wake_r, 4096)
                    continue
                sidecar = busy[stream]
                try:
                    data = _receive_bytes(stream)
                except (EOFError, OSError):
                    code = sidecar._proc.wait()
                    with self.changed:
                        if self._closed:    # killed by close(), which fails what is left
                            return
                        self._fail(RuntimeError(f"a worker process of the build ended (exit code {code}) before "
                                                "its job was done"), sidecar)
                    continue
                try:
                    reply = pickle.loads(data)
                except Exception as exc:   # noqa: BLE001 - the job's caller raises it
                    reply = (False, RuntimeError(f"a worker's reply does not unpickle: {exc!r}"))
                with self.changed:
                    self._finish(self._running.pop(sidecar), reply)

    def close(self) -> None:
        """Kill the processes and reap them; stop the reader. Jobs not finished fail.
        Again: nothing."""
        with self.changed:
            if self._closing:
                return
            self._closed = self._closing = True
        for sidecar in self.processes:
            sidecar.kill()
        os.write(self._wake_w, b"\0")
        if self._thread is not threading.current_thread():
            self._thread.join(5.0)
        with self.changed:
            failure = RuntimeError("the worker processes of the build were closed before the job was done")
            for job in [*self._running.values(), *self._queue]:
                if not job.finished:
                    self._finish(job, (False, failure))
            self._running.clear()
            self._queue.clear()
        for sidecar in self.processes:
            sidecar.close()
        for fd in (self._wake_r, self._wake_w):
            os.close(fd)


#: Seconds the processes of :func:`shared_pool` wait idle for the next build before they go.
SHARED_IDLE_S = 30.0
_shared: SidecarPool | None = None
_shared_lock = threading.Lock()


def shared_pool(workers: int) -> SidecarPool:
    """The process's pool of ``workers`` build workers, reused from build to build as loky
    reuses its workers: a script, a notebook or a test session that builds again finds them
    with their imports done. A new pool when there is none, it has another size, it lost a
    process or closed (killed after a failed build, or idle for :data:`SHARED_IDLE_S` s). It
    is closed when the interpreter exits."""
    global _shared
    with _shared_lock:
        from prs_geom.runtime.pool import user_threads

        if _shared is not None and (_shared.workers != workers or not _shared.usable
                                    or _shared.user_threads != user_threads()):
            _shared.close()
            _shared = None
        if _shared is None:
            _shared = SidecarPool(workers, SHARED_IDLE_S)
        return _shared


@atexit.register
def _close_shared() -> None:
    if _shared is not None:
        _shared.close()


# --------------------------------------------------------------------------- in the process
def main(argv: list[str] | None = None) -> None:
    """The process: ``PARENT_PID [MODULE:FUNCTION]`` (the warm-up, :class:`Sidecar`); jobs
    from standard input until it closes."""
    import importlib

    from prs_geom.runtime.pool import _timed, worker_init

    args = sys.argv[1:] if argv is None else argv
    replies = os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)   # a stray print goes to standard error, not into the replies
    worker_init(int(args[0]))
    if len(args) > 1:
        module, function = args[1].split(":")
        getattr(importlib.import_module(module), function)()
    requests = sys.stdin.buffer
    while True:
        try:
            request = _receive_bytes(requests)
        except EOFError:
            return
        try:    # a job that does not unpickle here (a function of a module this process cannot import) fails alone
            fn, fargs, fkwargs = pickle.loads(request)
            reply: tuple[bool, Any] = (True, _timed(fn, fargs, fkwargs))
        except Exception as exc:   # noqa: BLE001 - handed to the main process, which raises it
            reply = (False, exc)
        try:
            _send(replies, reply)
        except (pickle.PicklingError, TypeError, AttributeError) as exc:
            _send(replies, (False, RuntimeError(f"a job's result or error does not pickle: {exc}")))
        except BrokenPipeError:
            return


if __name__ == "__main__":
    main()
