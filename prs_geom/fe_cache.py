"""The cache of finite-element influence matrices (the only file I/O of the FE model).

The axisymmetric influence matrices of a part (:mod:`prs_geom.analysis.fe.teeth`) take
seconds to compute and depend only on the part's section: its thread profile, material,
loaded flanks with their contact points and Hertz bands, support and the number of teeth,
plus the mesh level and the code that computes them. They are computed once and kept, one
file per part, under a key derived from all of that:

* key = SHA-256 of ``repr(PartSection)`` (a frozen dataclass whose repr spells every float
  to full precision: profile, material, contact radii, Hertz semi-axes, support), the mesh
  level and teeth, the source of :mod:`prs_geom.analysis.fe` and the versions of
  scikit-fem, numpy and scipy. A change of any of them is a new key, so an entry is never
  stale; the stored description is compared with the current one on reading as well.
* Integrity: each file carries its key and a SHA-256 checksum of the key, the description
  and every stored array's dtype, shape and bytes. An entry whose checksum or key does not
  match (a matrix edited in place, a file copied under another name) is not trusted: it is
  recomputed and replaced, with a warning (:attr:`CachedInfluence.warnings`). The files
  are plain ``.npz`` read with ``allow_pickle=False``: no code can come from the cache.
* Where: ``$PRS_GEOM_CACHE/fe`` if set, else ``$XDG_CACHE_HOME/prs-geom/fe``, else
  ``~/.cache/prs-geom/fe``. Nothing is written anywhere else; files are written to a
  temporary name in that folder and renamed into place, so a reader never sees half a
  file. An unreadable or foreign entry is recomputed and replaced; a cache that cannot be
  written is reported (:attr:`CachedInfluence.stored`) and the matrices are used anyway.
* Graded pitch lists do not enter the key: the FE section is the constant-pitch thread
  (the grading is 0.01-0.5 um per tooth, far below what moves a compliance), so a design
  and its graded variants share their matrices. The roller and the nut of the two
  installations share theirs too.

Deleting the folder is always safe.
"""
from __future__ import annotations

import hashlib
import io
import os
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from prs_geom.model.io import write_file_atomic
from prs_geom.progress import ProgressFn, silent

__all__ = ["CachedInfluence", "cache_dir", "part_key", "cached_influence", "require_fe"]

#: Environment variable naming the cache folder (its ``fe`` subfolder holds the matrices).
CACHE_ENV = "PRS_GEOM_CACHE"
_ARRAYS = ("matrix", "axial_position_mm", "axial_sign", "body", "local", "contacts_per_ring", "band_half_width_mm")
_SCALARS = ("level", "teeth", "n_dofs", "body_per_pitch", "body_per_pitch_1d", "pitch_mm", "seconds")


def require_fe() -> None:
    """Raise :class:`~prs_geom.model.errors.EnvironmentFailure` with the install command when
    the optional extra ``fe`` (scikit-fem) is missing; before any work or output."""
    import importlib

    importlib.import_module("prs_geom.analysis.fe")   # raises with the install command


def cache_dir() -> Path:
    """The folder of the cached matrices (module docstring)."""
    root = os.environ.get(CACHE_ENV)
    if root:
        return Path(root).expanduser() / "fe"
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg else Path.home() / ".cache"
    return base / "prs-geom" / "fe"


def _code_fingerprint() -> str:
    """Hash of the FE package's source and the numerical libraries' versions."""
    from importlib.metadata import version

    import scipy

    import prs_geom.analysis.fe as fe

    h = hashlib.sha256()
    for path in sorted(Path(fe.__file__).parent.glob("*.py")):
        if path.name == "compliance.py":   # uses the matrices, does not compute them
            continue
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(f"skfem {version('scikit-fem')} numpy {np.__version__} scipy {scipy.__version__}".encode())
    return h.hexdigest()


def _description(section: Any, level: int, teeth: int) -> str:
    return f"{section!r}|level={int(level)}|teeth={int(teeth)}"


def part_key(section: Any, level: int, teeth: int, fingerprint: str | None = None) -> str:
    """The cache key of one part section (module docstring), 64 hex digits."""
    fp = _code_fingerprint() if fingerprint is None else fingerprint
    return hashlib.sha256((_description(section, level, teeth) + "|" + fp).encode()).hexdigest()


def _checksum(key: str, description: str, arrays: dict[str, np.ndarray]) -> str:
    """SHA-256 over the key, the description and each array's name, dtype, shape and bytes."""
    h = hashlib.sha256()
    h.update(key.encode())
    h.update(description.encode())
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def _stored_arrays(pi: Any, description: str) -> dict[str, np.ndarray]:
    return {"description": np.array(description), "part": np.array(pi.part), "flanks": np.array(list(pi.flanks)),
            "support_face": np.array(pi.support_face), **{k: np.asarray(getattr(pi, k)) for k in _ARRAYS},
            **{k: np.array(getattr(pi, k)) for k in _SCALARS}}


def _read(path: Path, description: str, key: str) -> tuple[Any, str]:
    """``(PartInfluence, "hit")`` from ``path``, or ``(None, why)``: "absent", "foreign"
    (another description: not ours to judge), "unreadable", or "tampered" (the stored key or
    checksum does not match what the file holds)."""
    from prs_geom.analysis.fe.teeth import PartInfluence

    try:
        with np.load(path, allow_pickle=False) as z:
            if str(z["description"]) != description:
                return None, "foreign"
            stored = {name: np.array(z[name]) for name in z.files if name not in ("key", "checksum")}
            if "checksum" not in z.files or str(z["key"]) != key or \
                    str(z["checksum"]) != _checksum(key, description, stored):
                return None, "tampered"
            kw: dict[str, Any] = {k: stored[k] for k in _ARRAYS}
            for k in _SCALARS:
                kw[k] = stored[k].item()
            return PartInfluence(part=str(stored["part"]), flanks=tuple(str(f) for f in stored["flanks"]),
                                 support_face=str(stored["support_face"]), **kw), "hit"
    except FileNotFoundError:
        return None, "absent"
    except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
        return None, "unreadable"


def _write(path: Path, pi: Any, description: str, key: str) -> bool:
    """Store ``pi`` atomically at ``path`` with its key and checksum; False when the folder
    cannot be written."""
    buf = io.BytesIO()
    arrays = _stored_arrays(pi, description)
    np.savez(buf, key=np.array(key), checksum=np.array(_checksum(key, description, arrays)), **arrays)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_file_atomic(path, buf.getvalue())
        return True
    except OSError:
        return False


@dataclass(frozen=True)
class CachedInfluence:
    """Influence matrices of a design, from the cache or computed and stored.

    Attributes
    ----------
    influence : InfluenceMatrices
        The screw, roller and nut matrices.
    hits : dict[str, bool]
        Per part: True when read from the cache.
    keys : dict[str, str]
        Per part: the cache key.
    folder : Path
        The cache folder.
    stored : bool
        False when a computed matrix could not be written to the cache (it is used anyway).
    seconds : float
        Wall time of this call (reading or computing), s.
    warnings : tuple of str
        One line per cache entry that failed its integrity check and was recomputed.
    """

    influence: Any
    hits: dict[str, bool]
    keys: dict[str, str]
    folder: Path
    stored: bool
    seconds: float
    warnings: tuple[str, ...] = ()

    def report(self) -> dict[str, Any]:
        """The ``cache`` entry of report.json's FE summary."""
        return {"folder": str(self.folder), "read_from_cache": dict(self.hits), "keys": dict(self.keys),
                "stored": self.stored, "seconds": self.seconds, "warnings": list(self.warnings)}


def cached_influence(design: Any, contact: Any = None, level: int | None = None, teeth: int | None = None,
                     progress: ProgressFn = silent, folder: Path | None = None) -> CachedInfluence:
    """The influence matrices of ``design`` (engaged teeth, converged level by default),
    read from the cache where present, else computed part by part and stored.

    ``progress("fe matrices", parts done, 3)`` after each part."""
    require_fe()
    from prs_geom.analysis.fe.teeth import CONVERGED_LEVEL, InfluenceMatrices, part_influence, part_sections

    t0 = time.perf_counter()
    level = CONVERGED_LEVEL if level is None else int(level)
    teeth = design.thread.engaged_teeth if teeth is None else int(teeth)
    folder = cache_dir() if folder is None else Path(folder)
    secs = part_sections(design, contact)
    fp = _code_fingerprint()
    parts, hits, keys, stored, warnings = {}, {}, {}, True, []
    progress("fe matrices", 0, 3)
    for i, name in enumerate(("screw", "roller", "nut")):
        desc = _description(secs[name], level, teeth)
        key = keys[name] = part_key(secs[name], level, teeth, fp)
        path = folder / f"{name}-{key[:32]}.npz"
        pi, status = _read(path, desc, key)
        hits[name] = pi is not None
        if status == "tampered":
            warnings.append(f"the cached {name} influence matrix {path} does not match its checksum (changed "
                            f"since prs-geom wrote it): not used; recomputed and replaced")
        if pi is None:
            pi = part_influence(secs[name], level, teeth)
            stored = _write(path, pi, desc, key) and stored
        parts[name] = pi
        progress("fe matrices", i + 1, 3)
    return CachedInfluence(InfluenceMatrices(parts["screw"], parts["roller"], parts["nut"]), hits, keys, folder,
                           stored, time.perf_counter() - t0, tuple(warnings))
