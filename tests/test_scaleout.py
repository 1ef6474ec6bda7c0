"""prs_geom.runtime.scaleout: serial, joblib and Dask give the same results bit for bit, in payload order.

One Dask LocalCluster serves the module (startup is the slow part); the ``scheduler="local"``
path starts one more, through a recording subclass that proves it is closed afterwards.
"""
from __future__ import annotations

import sys
import time
from types import SimpleNamespace

import distributed   # the test extra installs the dask extra: a missing one fails here, loudly
import numpy as np
import pytest

from prs_geom.runtime import scaleout
from prs_geom.model.errors import DesignError, EnvironmentFailure
from prs_geom.runtime.scaleout import (DASK_INSTALL, Backend, local_cluster_options, plan_chunks, resolve_backend,
                               run_chunks, spawn_seeds)

SEED = 20240611
ITEMS, CHUNK = 11, 3          # 4 chunks: 3 + 3 + 3 + 2 items
SIZE = 200                    # large enough that a multithreaded BLAS splits the work


def solve_chunk(payload):
    """Per item: a random SPD system from the chunk's own stream, a BLAS product and a LAPACK
    solve. Returns (chunk index, solutions (items, SIZE), the BLAS thread limit seen)."""
    from threadpoolctl import threadpool_info

    k, seed, items, delay = payload
    rng = np.random.default_rng(seed)
    out = np.empty((len(items), SIZE))
    for r, _ in enumerate(items):
        a = rng.standard_normal((SIZE, SIZE))
        m = a @ a.T + SIZE * np.eye(SIZE)
        out[r] = np.linalg.solve(m, rng.standard_normal(SIZE))
    # the first chunk finishes last, so completion order differs from payload order
    time.sleep(delay)
    threads = max(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
    return k, out, threads


def fail_on_two(payload):
    if payload == 2:
        raise ValueError("payload 2 is bad")
    return payload * 10


def payloads(delay_first: float = 0.0):
    chunks = plan_chunks(ITEMS, CHUNK)
    seeds = spawn_seeds(SEED, len(chunks))
    return [(k, seeds[k], c, delay_first if k == 0 else 0.0) for k, c in enumerate(chunks)]


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(**local_cluster_options(2)) as c:
        yield c


@pytest.fixture(scope="module")
def serial():
    calls = []
    res = run_chunks(solve_chunk, payloads(), workers=1, progress=lambda *a: calls.append(a), stage="mc",
                     sizes=[len(c) for c in plan_chunks(ITEMS, CHUNK)])
    return res, calls


def _check_same(results, reference):
    assert [r[0] for r in results] == [0, 1, 2, 3]           # payload order
    for (_, a, _), (_, b, _) in zip(results, reference):
        assert a.dtype == np.float64 and a.shape == b.shape
        assert np.array_equal(a, b)                           # bit for bit, not allclose
    assert all(r[2] == 1 for r in results)                    # BLAS pinned to one thread in the task


def _check_progress(calls, stage="mc"):
    assert [c[0] for c in calls] == [stage] * len(calls)
    done = [c[1] for c in calls]
    assert done == sorted(done) and len(set(done)) == len(done)
    assert done[-1] == ITEMS and {c[2] for c in calls} == {ITEMS}


# --------------------------------------------------------------------------- chunks and seeds
def test_plan_chunks_depends_on_items_and_size_only():
    assert plan_chunks(10, 4) == [range(0, 4), range(4, 8), range(8, 10)]
    assert plan_chunks(3, 5) == [range(0, 3)]
    assert plan_chunks(0, 5) == []
    with pytest.raises(DesignError, match="chunk_size = 0: must be a whole number >= 1"):
        plan_chunks(10, 0)
    with pytest.raises(DesignError, match="n_items"):
        plan_chunks(2.5, 1)


def test_spawn_seeds_are_the_seed_sequence_children_and_stable_in_count():
    seeds = spawn_seeds(7, 3)
    ref = np.random.SeedSequence(7).spawn(3)
    assert [s.generate_state(4).tolist() for s in seeds] == [s.generate_state(4).tolist() for s in ref]
    # more chunks do not change the streams of the first ones
    more = spawn_seeds(7, 5)
    assert [s.generate_state(4).tolist() for s in more[:3]] == [s.generate_state(4).tolist() for s in seeds]
    assert len({tuple(s.generate_state(2)) for s in more}) == 5
    with pytest.raises(DesignError, match="seed"):
        spawn_seeds(-1, 2)


def test_backend_resolution():
    assert resolve_backend(5, workers=1) == Backend("serial")
    assert resolve_backend(1) == Backend("serial")                       # one payload: no pool
    assert resolve_backend(3, workers=4) == Backend("joblib", 3)         # never more than payloads
    assert resolve_backend(8, workers=2).describe() == "joblib, 2 processes"
    assert resolve_backend(1, dask_workers=2) == Backend("dask", 2, "local")
    assert resolve_backend(4, scheduler="tcp://10.0.0.1:8786") == Backend("dask", None, "tcp://10.0.0.1:8786")
    with pytest.raises(DesignError, match="workers = 0"):
        resolve_backend(4, workers=0)
    with pytest.raises(DesignError, match="cannot be combined"):
        resolve_backend(4, workers=2, scheduler="local")
    with pytest.raises(DesignError, match="scheduler address such as tcp://"):
        resolve_backend(4, scheduler="localhost")
    with pytest.raises(DesignError, match="brings its own workers"):
        resolve_backend(4, scheduler="tcp://10.0.0.1:8786", dask_workers=2)
    with pytest.raises(DesignError, match="one size per payload"):
        run_chunks(fail_on_two, [0, 1], workers=1, sizes=[1])


# --------------------------------------------------------------------------- bit for bit
def test_serial_run(serial):
    results, calls = serial
    assert [r[1].shape for r in results] == [(3, SIZE)] * 3 + [(2, SIZE)]
    # the chunk streams differ: no two chunks drew the same systems
    assert len({r[1][0, 0] for r in results}) == 4
    assert [c[1] for c in calls] == [3, 6, 9, 11]
    _check_same(results, results)


def test_joblib_equals_serial_bit_for_bit(serial):
    calls = []
    res = run_chunks(solve_chunk, payloads(delay_first=0.3), workers=2, progress=lambda *a: calls.append(a),
                     stage="mc", sizes=[3, 3, 3, 2])
    _check_same(res, serial[0])
    _check_progress(calls)


def test_dask_cluster_by_address_equals_serial_bit_for_bit(serial, cluster):
    calls = []
    res = run_chunks(solve_chunk, payloads(delay_first=0.5), scheduler=cluster.scheduler_address,
                     progress=lambda *a: calls.append(a), stage="mc", sizes=[3, 3, 3, 2])
    _check_same(res, serial[0])
    _check_progress(calls)
    # progress follows completion: the 2-item chunk 3 completed before the slow 3-item chunk 0
    # (payload order would read 3, 6, 9, 11), while the results above are in payload order
    assert [c[1] for c in calls][-2:] == [8, 11]


def test_dask_client_handed_in_is_left_open(serial, cluster):
    with distributed.Client(cluster, set_as_default=False) as client:
        res = run_chunks(solve_chunk, payloads(), scheduler=client)
        _check_same(res, serial[0])
        assert client.status == "running"


def test_local_dask_cluster_is_started_and_closed(serial, monkeypatch):
    started = []

    class Recording(distributed.LocalCluster):
        def __init__(self, **kwargs):
            started.append(kwargs)
            super().__init__(**kwargs)
            started.append(self)

    fake = SimpleNamespace(LocalCluster=Recording, Client=distributed.Client, as_completed=distributed.as_completed)
    monkeypatch.setattr(scaleout, "_import_distributed", lambda: fake)
    res = run_chunks(solve_chunk, payloads(), dask_workers=2)
    _check_same(res, serial[0])
    kwargs, cl = started
    assert kwargs["n_workers"] == 2 and kwargs["threads_per_worker"] == 1 and kwargs["processes"] is True
    assert cl.status.name == "closed"


def test_task_errors_reach_the_caller(cluster):
    assert run_chunks(fail_on_two, [0, 1, 3], workers=2) == [0, 10, 30]
    with pytest.raises(ValueError, match="payload 2 is bad"):
        run_chunks(fail_on_two, [0, 1, 2, 3], workers=2)
    with pytest.raises(ValueError, match="payload 2 is bad"):
        run_chunks(fail_on_two, [0, 1, 2, 3], scheduler=cluster.scheduler_address)


# --------------------------------------------------------------------------- environment
def test_missing_dask_extra_names_the_install_command(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)    # `import distributed` now fails
    for kwargs in ({"dask_workers": 2}, {"scheduler": "tcp://127.0.0.1:8786"}, {"scheduler": "local"}):
        with pytest.raises(EnvironmentFailure) as info:
            run_chunks(fail_on_two, [0, 1], **kwargs)
        assert DASK_INSTALL in str(info.value) and 'pip install "prs-geom[dask]"' in str(info.value)
    # joblib and serial need no Dask
    assert run_chunks(fail_on_two, [0, 1], workers=1) == [0, 10]


def test_unreachable_scheduler_is_an_environment_failure(monkeypatch):
    monkeypatch.setattr(scaleout, "CONNECT_TIMEOUT_S", 0.5)
    with pytest.raises(EnvironmentFailure, match=r"cannot connect to the Dask scheduler at tcp://127\.0\.0\.1:9"):
        run_chunks(fail_on_two, [0, 1], scheduler="tcp://127.0.0.1:9")
