"""Wall-clock timing shared by the benchmark scripts (run from any folder: each script puts
its own folder first on sys.path, so ``from timing import ...`` finds this module)."""
from __future__ import annotations

import gc
import statistics
import time
from typing import Any, Callable


def run_timed(fn: Callable[[], Any], repeats: int = 1, collect: bool = False) -> tuple[list[float], Any]:
    """Seconds of each of ``repeats`` calls of ``fn`` and the last call's result;
    ``collect`` runs the garbage collector before each call."""
    times, out = [], None
    for _ in range(repeats):
        if collect:
            gc.collect()
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return times, out


def median_time(fn: Callable[[], Any], repeats: int = 7) -> float:
    """Median seconds of ``repeats`` calls (robust to a noisy machine)."""
    return statistics.median(run_timed(fn, repeats)[0])


def best_time(fn: Callable[[], Any], repeats: int = 5, collect: bool = False) -> float:
    """Smallest seconds of ``repeats`` calls (the least disturbed run)."""
    return min(run_timed(fn, repeats, collect)[0])
