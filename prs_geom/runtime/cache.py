"""A keyed store of numpy arrays on disk: checksummed entries, atomic writes, no pickles.

A stage whose results are costly and depend only on its inputs keeps them here under a key
the caller derives from those inputs (and from the source of the code that computes them):
the store never interprets the key material, it only guarantees what it gives back.

* An entry is one ``.npz`` file ``<name>-<key[:32]>.npz`` in the store's folder holding the
  caller's arrays plus ``description`` (the caller's full, human-readable key material),
  ``key`` and ``checksum``: SHA-256 over the key, the description and each array's name,
  dtype, shape and bytes (:func:`checksum`).
* Reading (:meth:`ArrayStore.read`) returns the arrays only when the stored description is
  the caller's, the stored key is the caller's and the checksum matches; otherwise it says
  why (:data:`READ_STATUSES`). Files are read with ``allow_pickle=False``: no code can come
  from the cache.
* Writing (:meth:`ArrayStore.write`) goes to a temporary name in the folder and is renamed
  into place, so a reader never sees half a file; a folder that cannot be written is
  reported (False), never raised.
* ``$PRS_GEOM_NO_CACHE`` set (``prs-geom build --no-cache``): no entry is read, every
  caller computes afresh and writes its entries again.
* Where: :func:`stage_dir` ``(stage)`` = ``$PRS_GEOM_CACHE/<stage>`` if set, else
  ``$XDG_CACHE_HOME/prs-geom/<stage>``, else ``~/.cache/prs-geom/<stage>``. Deleting any of
  these folders is always safe.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator

import numpy as np

from prs_geom.model.io import atomic_path

__all__ = ["CACHE_ENV", "NO_CACHE_ENV", "READ_STATUSES", "ArrayStore", "cache_root", "checksum", "file_sha256",
           "reads_disabled", "reads_enabled", "stage_dir"]

#: Environment variable naming the cache root (one subfolder per stage).
CACHE_ENV = "PRS_GEOM_CACHE"
#: Environment variable that, set to anything but empty or ``0``, makes every read a miss.
NO_CACHE_ENV = "PRS_GEOM_NO_CACHE"
#: What :meth:`ArrayStore.read` reports: the entry was used ("hit"), there is none
#: ("absent"), it holds another description ("foreign": not ours to judge), it cannot be
#: read ("unreadable"), or its key or checksum does not match its contents ("tampered").
READ_STATUSES = ("hit", "absent", "foreign", "unreadable", "tampered")
_RESERVED = ("description", "key", "checksum")


def reads_enabled() -> bool:
    """Whether reads may hit: not while ``$PRS_GEOM_NO_CACHE`` is set (:func:`reads_disabled`)."""
    return os.environ.get(NO_CACHE_ENV, "").strip() in ("", "0")


@contextlib.contextmanager
def reads_disabled() -> Iterator[None]:
    """Within the block, every read is a miss (``$PRS_GEOM_NO_CACHE`` set, so worker
    processes started meanwhile miss too); the environment is restored after."""
    saved = os.environ.get(NO_CACHE_ENV)
    os.environ[NO_CACHE_ENV] = "1"
    try:
        yield
    finally:
        if saved is None:
            os.environ.pop(NO_CACHE_ENV, None)
        else:
            os.environ[NO_CACHE_ENV] = saved


def cache_root() -> Path:
    """The root folder of every stage's cache (module docstring: where)."""
    root = os.environ.get(CACHE_ENV)
    if root:
        return Path(root).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "prs-geom"


def stage_dir(stage: str) -> Path:
    """The cache folder of one stage, ``cache_root() / stage``."""
    return cache_root() / stage


def file_sha256(path: Path) -> str:
    """SHA-256 (hex) of a file's bytes, read in 4 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 22), b""):
            h.update(block)
    return h.hexdigest()


def checksum(key: str, description: str, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 (hex) over the key, the description and each array's name, dtype, shape and
    bytes, arrays in name order."""
    h = hashlib.sha256()
    h.update(key.encode())
    h.update(description.encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.reshape(-1).view(np.uint8))     # the bytes, without a copy
    return h.hexdigest()


@dataclass(frozen=True)
class ArrayStore:
    """The entries of one folder (module docstring).

    Attributes
    ----------
    folder : Path
        Where the entries live; created on the first write.
    """

    folder: Path

    def path(self, name: str, key: str) -> Path:
        """The file of entry ``name`` under ``key`` (64 hex digits; 32 name the file)."""
        return Path(self.folder) / f"{name}-{key[:32]}.npz"

    def read(self, name: str, key: str, description: str) -> tuple[dict[str, np.ndarray] | None, str]:
        """``(arrays, "hit")`` of the entry, the reserved ``description``, ``key`` and
        ``checksum`` left out; else ``(None, status)`` with a status of :data:`READ_STATUSES`
        (``"absent"`` for every entry while ``$PRS_GEOM_NO_CACHE`` is set)."""
        if not reads_enabled():
            return None, "absent"
        try:
            with np.load(self.path(name, key), allow_pickle=False) as z:
                if str(z["description"]) != description:
                    return None, "foreign"
                stored = {item: z[item] for item in z.files if item not in ("key", "checksum")}
                if "checksum" not in z.files or str(z["key"]) != key or \
                        str(z["checksum"]) != checksum(key, description, stored):
                    return None, "tampered"
        except FileNotFoundError:
            return None, "absent"
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
            return None, "unreadable"
        del stored["description"]
        return stored, "hit"

    def write(self, name: str, key: str, description: str, arrays: dict[str, np.ndarray]) -> bool:
        """Store ``arrays`` (names other than ``description``, ``key``, ``checksum``) as entry
        ``name`` under ``key``, atomically; False when the folder cannot be written."""
        clash = set(arrays) & set(_RESERVED)
        if clash:
            raise ValueError(f"array names reserved by the store: {sorted(clash)}")
        stored = {"description": np.array(description), **arrays}
        target = self.path(name, key)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            # written to the file as it is made (a record of a build's meshes is tens of MB:
            # no second copy in memory), then renamed into place
            with atomic_path(target) as tmp, open(tmp, "wb") as fh:
                np.savez(fh, key=np.array(key), checksum=np.array(checksum(key, description, stored)), **stored)
            return True
        except OSError:
            return False
