"""The plot process of a rebuild: one worker, started before the stage records are read.

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

Only the build uses it, only when ``$PRS_GEOM_WORKERS`` allows worker processes, and only
for the plots (:meth:`prs_geom.pipeline.BuildContext.add_plot`): their files are the same
bytes wherever they are drawn (``tests/test_build_cache.py``).
"""
from __future__ import annotations

import os
import pickle
import select
import subprocess
import sys
from typing import Any, BinaryIO, Callable

__all__ = ["Sidecar", "main"]

#: Bytes of the length prefix of each message.
_HEADER = 8


def _send(stream: BinaryIO, obj: Any) -> None:
    data = pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL)
    view = memoryview(len(data).to_bytes(_HEADER, "little") + data)
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
    """One plot process (module docstring), started at construction.

    Parameters
    ----------
    warm : callable or None
        A module-level function the process calls with no arguments before it takes jobs
        (it is named to the process, not pickled): the build's is
        :func:`prs_geom.exports.plots.warm_up`, matplotlib imported and its fonts loaded.
    """

    def __init__(self, warm: Callable[[], None] | None = None) -> None:
        from prs_geom.runtime.pool import _blocked

        argv = [sys.executable, "-m", "prs_geom.runtime.sidecar", str(os.getpid())]
        if warm is not None:
            argv.append(f"{warm.__module__}:{warm.__qualname__}")
        with _blocked():    # the child starts with SIGINT and SIGTERM blocked (pool._blocked)
            # unbuffered: what select() sees on the pipe is all there is (finished())
            self._proc = subprocess.Popen(argv, stdin=subprocess.PIPE, stdout=subprocess.PIPE, bufsize=0)
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
