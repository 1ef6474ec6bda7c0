"""Chunked parallel map: serial, joblib (loky processes) or Dask, with the same results bit for bit.

A study (tolerance Monte Carlo, design-space sweep) cuts its work into *chunks*, one
picklable payload each, and hands a top-level function ``task(payload) -> result`` to
:func:`run_chunks`, which returns the results in payload order whatever backend ran them
and in whatever order the chunks finished (docs/scaleout.md).

Bit-identical results across backends and worker counts rest on four rules:

* the chunks do not depend on the worker count: the caller fixes the chunk size
  (:func:`plan_chunks`), never ``n_items / workers``;
* every chunk draws its random numbers from its own stream, ``SeedSequence(seed).spawn``
  (:func:`spawn_seeds`), so a chunk's numbers do not depend on which process runs it or
  what ran there before;
* the results are gathered in payload order, so any reduction over them sums in a fixed order;
* BLAS and OpenMP run one thread inside every task (threadpoolctl), in the workers and in the
  serial run alike: a multithreaded BLAS may split a reduction differently with another
  thread count and change the last bits.

Dask is an optional extra (``pip install "prs-geom[dask]"``), imported only when a Dask
backend is asked for; without it :class:`~prs_geom.model.errors.EnvironmentFailure` names
the install command (exit code 3 on the command line).

Leaf-ish module: it imports nothing of prs_geom but :mod:`prs_geom.runtime.progress`,
:mod:`prs_geom.runtime.pool` (the worker pool) and :mod:`prs_geom.model.errors`, so any layer
may use it. numpy, joblib, threadpoolctl and Dask
are imported on use, which keeps the command-line start-up light.
"""
from __future__ import annotations

import logging
import numbers
import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Sequence, TypeVar

from prs_geom.model.errors import DesignError, EnvironmentFailure
from prs_geom.runtime.progress import ProgressFn

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

__all__ = ["DASK_INSTALL", "Backend", "available_cpus", "plan_chunks", "spawn_seeds", "resolve_backend",
           "run_chunks", "local_cluster_options", "require_dask"]

P = TypeVar("P")
R = TypeVar("R")

#: The install command of the optional Dask extra, named in every message about it.
DASK_INSTALL = 'pip install "prs-geom[dask]"'
#: Seconds to wait for a remote Dask scheduler before giving up (exit code 3 on the CLI).
CONNECT_TIMEOUT_S = 10


# --------------------------------------------------------------------------- determinism
def plan_chunks(n_items: int, chunk_size: int) -> list[range]:
    """Cut ``n_items`` items into consecutive chunks of ``chunk_size`` (the last one shorter).

    The chunks depend on these two numbers only, never on the worker count, so that a chunked
    study gives the same results on any backend.

    Parameters
    ----------
    n_items : int
        Number of items (samples, design points), >= 0.
    chunk_size : int
        Items per chunk, >= 1.

    Returns
    -------
    list of range
        Item indices of each chunk, in order; empty when ``n_items`` is 0.
    """
    _whole("n_items", n_items, 0)
    _whole("chunk_size", chunk_size, 1)
    return [range(start, min(start + chunk_size, n_items)) for start in range(0, n_items, chunk_size)]


def spawn_seeds(seed: int, n_chunks: int) -> list["np.random.SeedSequence"]:
    """One independent random stream per chunk: ``SeedSequence(seed).spawn(n_chunks)``.

    Chunk ``k`` gets the same stream whatever runs it, so its random numbers, and with them
    the study's results, do not depend on the backend or the worker count. Build a generator
    in the task with ``np.random.default_rng(seeds[k])``.

    Parameters
    ----------
    seed : int
        Root seed of the study, >= 0 (report it: it reproduces the study).
    n_chunks : int
        Number of chunks, >= 0.

    Returns
    -------
    list of numpy.random.SeedSequence
        ``n_chunks`` child sequences, chunk 0 first.
    """
    import numpy as np

    _whole("seed", seed, 0)
    _whole("n_chunks", n_chunks, 0)
    return np.random.SeedSequence(seed).spawn(n_chunks)


def _whole(name: str, value: Any, least: int) -> int:
    """``value`` as an int; numpy integers count, bools and floats do not."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < least:
        raise DesignError(name, value, f"must be a whole number >= {least}")
    return int(value)


# --------------------------------------------------------------------------- backends
def available_cpus() -> int:
    """CPUs this process may run on (its affinity mask where the OS has one, else
    ``os.cpu_count()``): the default number of joblib and local Dask workers."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):  # not Linux
        return max(1, os.cpu_count() or 1)


@dataclass(frozen=True)
class Backend:
    """Where :func:`run_chunks` runs the chunks.

    Attributes
    ----------
    kind : {"serial", "joblib", "dask"}
        In this process, in joblib's loky worker processes, or on a Dask cluster.
    workers : int or None
        Processes (joblib, or the workers of a local Dask cluster); None for a Dask
        scheduler given by address or client, which brings its own workers.
    scheduler : str or None
        ``"local"`` (a LocalCluster started and closed by :func:`run_chunks`), the scheduler
        address, ``"client"`` for a ``distributed.Client`` handed in, None otherwise.
    """

    kind: str
    workers: int | None = None
    scheduler: str | None = None

    def describe(self) -> str:
        """One line for a log: ``joblib, 4 processes``, ``dask at tcp://host:8786``..."""
        if self.kind == "serial":
            return "serial, in this process"
        if self.kind == "joblib":
            return f"joblib, {self.workers} processes"
        if self.scheduler == "local":
            return f"dask, local cluster of {self.workers} processes"
        if self.scheduler == "client":
            return "dask, through the client handed in"
        return f"dask at {self.scheduler}"


def _is_client(obj: Any) -> bool:
    # duck-typed so that this module does not import distributed to recognise a Client
    return not isinstance(obj, str) and callable(getattr(obj, "submit", None)) \
        and callable(getattr(obj, "gather", None))


def resolve_backend(n_payloads: int, *, workers: int | None = None, scheduler: Any = None,
                    dask_workers: int | None = None) -> Backend:
    """The backend :func:`run_chunks` uses for these arguments (it validates them).

    * ``scheduler`` (``"local"``, an address such as ``"tcp://host:8786"``, or a
      ``distributed.Client``) or ``dask_workers`` (a local cluster of that many processes):
      Dask, however small the job, since it was asked for by name;
    * otherwise ``workers`` processes (default :func:`available_cpus`), never more than
      there are payloads; serial when that leaves one.

    Raises
    ------
    DesignError
        A worker count that is not a whole number >= 1, a scheduler that is neither
        ``"local"``, an address nor a client, or joblib and Dask options together.
    """
    _whole("n_payloads", n_payloads, 0)
    if workers is not None:
        _whole("workers", workers, 1)
    if dask_workers is not None:
        _whole("dask_workers", dask_workers, 1)
    if scheduler is None and dask_workers is None:
        n = min(workers if workers is not None else available_cpus(), n_payloads)
        return Backend("joblib", n) if n > 1 else Backend("serial")
    if workers is not None:
        raise DesignError("workers", workers, "sets joblib processes and cannot be combined with a Dask "
                                              "scheduler or Dask workers")
    if scheduler is None or scheduler == "local":
        return Backend("dask", dask_workers or available_cpus(), "local")
    if _is_client(scheduler):
        if dask_workers is not None:
            raise DesignError("dask_workers", dask_workers, "starts a local cluster; a Dask client "
                                                            "brings its own workers")
        return Backend("dask", None, "client")
    if not isinstance(scheduler, str) or "://" not in scheduler:
        raise DesignError("scheduler", scheduler if isinstance(scheduler, str) else repr(scheduler),
                          'must be "local" or a Dask scheduler address such as tcp://host:8786')
    if dask_workers is not None:
        raise DesignError("dask_workers", dask_workers, f"starts a local cluster; the scheduler at "
                                                        f"{scheduler} brings its own workers")
    return Backend("dask", None, scheduler)


# --------------------------------------------------------------------------- the map
def _pinned_call(task: Callable[[Any], Any], payload: Any) -> Any:
    """``task(payload)`` with BLAS and OpenMP limited to one thread (module doc: why).

    Runs in the worker process; the limits are set per call because a task may load a new
    BLAS (e.g. scipy's) on first use, which a limit set once at worker start-up would miss.
    """
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1):
        return task(payload)


def run_chunks(task: Callable[[P], R], payloads: Sequence[P], *, workers: int | None = None,
               scheduler: Any = None, dask_workers: int | None = None,
               progress: ProgressFn | None = None, stage: str = "chunks",
               sizes: Sequence[int] | None = None) -> list[R]:
    """``[task(p) for p in payloads]``, run serially, in joblib processes or on Dask.

    Parameters
    ----------
    task : callable
        ``task(payload) -> result``: a top-level (importable, picklable) function, or a
        ``functools.partial`` of one. It must not modify its payload (in this process it
        is the caller's object) and runs with one BLAS thread.
    payloads : sequence
        One picklable payload per chunk, e.g. ``(seed_sequence, item_range, model)``.
    workers : int, optional
        joblib (loky) worker processes; default :func:`available_cpus`. 1, or a single
        payload, runs in this process.
    scheduler : str or distributed.Client, optional
        Dask instead of joblib: ``"local"`` starts a LocalCluster (processes, one thread
        each) and closes it afterwards, ``"tcp://host:port"`` connects to a running
        scheduler (its workers need prs_geom installed), a ``distributed.Client`` is used as
        it is and left open.
    dask_workers : int, optional
        Processes of the local Dask cluster (implies ``scheduler="local"``); default
        :func:`available_cpus`.
    progress : callable, optional
        ``progress(stage, done, total)`` after each chunk completes, in completion order
        for Dask and in payload order for joblib; ``done`` counts up to ``total``.
    stage : str
        Stage name passed to ``progress``.
    sizes : sequence of int, optional
        Items in each chunk, so that ``done``/``total`` count items (samples, points); one
        per chunk when omitted.

    Returns
    -------
    list
        The results, in payload order.

    Raises
    ------
    EnvironmentFailure
        Dask asked for but not installed (the message gives ``pip install "prs-geom[dask]"``)
        or a scheduler that cannot be reached.
    DesignError
        Invalid backend options (:func:`resolve_backend`) or ``sizes`` of the wrong length.
    Exception
        Whatever ``task`` raised, re-raised here; the remaining chunks are cancelled.
    """
    payloads = list(payloads)
    n = len(payloads)
    if sizes is None:
        weights = [1] * n
    else:
        weights = [_whole(f"sizes[{i}]", s, 0) for i, s in enumerate(sizes)]
        if len(weights) != n:
            raise DesignError("sizes", list(sizes), f"must give one size per payload ({n})")
    backend = resolve_backend(n, workers=workers, scheduler=scheduler, dask_workers=dask_workers)
    total = sum(weights)
    done = [0]

    def tick(i: int) -> None:
        done[0] += weights[i]
        if progress is not None:
            progress(stage, done[0], total)

    if n == 0:
        return []
    if backend.kind == "serial":
        out = []
        for i, p in enumerate(payloads):
            out.append(_pinned_call(task, p))
            tick(i)
        return out
    if backend.kind == "joblib":
        return _run_joblib(task, payloads, backend.workers or 1, tick)
    return _run_dask(task, payloads, backend, scheduler, tick)


def _run_joblib(task: Callable[[Any], Any], payloads: list[Any], n_jobs: int,
                tick: Callable[[int], None]) -> list[Any]:
    """The chunks in the build's worker pool (:mod:`prs_geom.runtime.pool`: joblib's loky
    processes, which do not re-run the caller's script, killed on an error or interrupt)."""
    from prs_geom.runtime.pool import Background

    with Background(n_jobs) as pool:
        jobs = [pool.submit(_pinned_call, task, p) for p in payloads]
        out = []
        # taken in payload order, so the results need no sorting
        for i, job in enumerate(jobs):
            out.append(job.result())
            tick(i)
    return out


def local_cluster_options(n_workers: int) -> dict[str, Any]:
    """Keyword arguments of the ``distributed.LocalCluster`` that ``scheduler="local"`` starts:
    ``n_workers`` processes of one thread each (one chunk at a time per process, like the
    joblib workers), only errors logged, and the scheduler's HTTP server (it runs even
    without the dashboard) on a free port: the fixed default 8787 collides with any other
    cluster on the machine."""
    return {"n_workers": n_workers, "threads_per_worker": 1, "processes": True, "dashboard_address": ":0",
            "silence_logs": logging.ERROR}


def require_dask() -> None:
    """Raise :class:`EnvironmentFailure` naming the install command when the Dask extra is
    missing: for the command line to check before any work starts."""
    _import_distributed()


def _import_distributed() -> Any:
    """The ``distributed`` module, or :class:`EnvironmentFailure` naming the install command."""
    try:
        import distributed
    except ImportError as exc:
        raise EnvironmentFailure(f"running on Dask needs the optional extra 'dask', which is not installed "
                                 f"({exc}); install it with: {DASK_INSTALL}") from None
    return distributed


def _run_dask(task: Callable[[Any], Any], payloads: list[Any], backend: Backend, scheduler: Any,
              tick: Callable[[int], None]) -> list[Any]:
    distributed = _import_distributed()
    owned: list[Any] = []   # what this call opened and must close, last opened first
    quiet = logging.getLogger("distributed")
    level = quiet.level
    try:
        if backend.scheduler == "client":
            client = scheduler
        elif backend.scheduler == "local":
            # SIGINT and SIGTERM ignored while the cluster starts, so that its nanny and worker
            # processes inherit the ignored signals: a Ctrl-C to the process group then reaches
            # only this process, which closes the cluster, instead of a hundred lines of
            # tracebacks from the cluster's processes (one during the start-up is lost)
            from prs_geom.runtime.pool import signals_ignored

            with signals_ignored(True):
                cluster = distributed.LocalCluster(**local_cluster_options(backend.workers or 1))
            owned.append(cluster)
            client = distributed.Client(cluster, set_as_default=False)
            owned.append(client)
        else:
            try:
                client = distributed.Client(backend.scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
            except (OSError, TimeoutError) as exc:
                raise EnvironmentFailure(f"cannot connect to the Dask scheduler at {backend.scheduler}: "
                                         f"{exc or type(exc).__name__}") from None
            owned.append(client)
        # pure=False: payloads are not hashed into keys (they may be large), and equal
        # payloads still run once each, as in the other backends
        futures = [client.submit(_pinned_call, task, p, pure=False) for p in payloads]
        index = {f.key: i for i, f in enumerate(futures)}
        out: list[Any] = [None] * len(payloads)
        try:
            for future, result in distributed.as_completed(futures, loop=client.loop, with_results=True):
                i = index[future.key]
                out[i] = result
                tick(i)
        except BaseException:
            # an error or an interrupt: the command prints one line for it; the cluster's
            # complaints about work cut off while closing (CRITICAL "lost data" logs) are
            # not the user's business
            quiet.setLevel(logging.CRITICAL + 1)
            client.cancel(futures)
            raise
        return out
    finally:
        try:
            for obj in reversed(owned):
                obj.close()
        finally:
            quiet.setLevel(level)
