"""prs_geom.runtime.memwatch: the free heap handed back to the system."""
from __future__ import annotations

import ctypes.util
import os
import sys

import numpy as np
import pytest

from prs_geom.runtime.memwatch import _rss, release_free_heap


@pytest.mark.skipif(not sys.platform.startswith("linux") or ctypes.util.find_library("c") != "libc.so.6",
                    reason="malloc_trim is glibc's")
def test_release_free_heap_hands_freed_blocks_back():
    """64 MB of 64 KB blocks (below glibc's mmap threshold: they live in the heap), all freed
    but the last one, which pins the heap's top so that glibc cannot shrink it by itself: the
    freed memory stays resident until release_free_heap gives it back."""
    blocks = [np.ones(8192) for _ in range(1024)]
    last = blocks[-1]
    del blocks
    held = _rss(os.getpid())
    release_free_heap()
    freed = held - _rss(os.getpid())
    assert freed > 48 * 2**20, f"{freed / 2**20:.1f} MB handed back"
    assert last.sum() == 8192.0
