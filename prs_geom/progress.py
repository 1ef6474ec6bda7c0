"""Minimal progress reporting to stderr for long stages (no extra dependency)."""
from __future__ import annotations

import sys
import time
from typing import Callable

#: A progress callback: (stage, done, total).
ProgressFn = Callable[[str, int, int], None]


def silent(stage: str, done: int, total: int) -> None:
    """A progress callback that prints nothing."""


class StderrProgress:
    """Prints ``stage: done/total`` lines to stderr, at most every ``interval`` seconds
    and always at completion."""

    def __init__(self, interval: float = 0.5) -> None:
        self.interval = interval
        self._last = 0.0

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if done >= total or now - self._last >= self.interval:
            self._last = now
            print(f"  {stage}: {done}/{total}", file=sys.stderr, flush=True)
