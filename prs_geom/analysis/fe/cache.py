"""The finite-element influence matrices as an entry of the runtime's keyed array store.

The axisymmetric influence matrices of a part (:mod:`prs_geom.analysis.fe.teeth`) take
seconds to compute and depend only on the part's section: its thread profile, material,
loaded flanks with their contact points and Hertz bands, support and the number of teeth,
plus the mesh level and the code that computes them. They are computed once and kept, one
entry per part, in the store of :mod:`prs_geom.runtime.cache` (which owns the file format,
the checksums, the atomic writes and the folder ``$PRS_GEOM_CACHE/fe``); this module owns
the key material and the conversion of a :class:`~prs_geom.analysis.fe.teeth.PartInfluence`
to and from arrays:

* key = SHA-256 of ``repr(PartSection)`` (a frozen dataclass whose repr spells every float
  to full precision: profile, material, contact radii, Hertz semi-axes, support), the mesh
  level and teeth, the source of :mod:`prs_geom.analysis.fe` (the modules that compute the
  matrices) and the versions of scikit-fem, numpy and scipy (:func:`part_key`). A change of
  any of them is a new key, so an entry is never stale; the stored description is compared
  with the current one on reading as well.
* An entry that fails its integrity check (a matrix edited in place, a file copied under
  another name) is not trusted: it is recomputed and replaced, with a warning
  (:attr:`CachedInfluence.warnings`). An unreadable or foreign entry is recomputed and
  replaced; a cache that cannot be written is reported (:attr:`CachedInfluence.stored`) and
  the matrices are used anyway.
* Graded pitch lists do not enter the key: the FE section is the constant-pitch thread
  (the grading is 0.01-0.5 um per tooth, far below what moves a compliance), so a design
  and its graded variants share their matrices. The roller and the nut of the two
  installations share theirs too.
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from prs_geom.runtime.cache import ArrayStore, stage_dir
from prs_geom.runtime.progress import ProgressFn, silent

__all__ = ["CachedInfluence", "STAGE", "cache_dir", "code_fingerprint", "part_key", "cached_influence",
           "require_fe", "influence_arrays", "influence_from_arrays"]

#: The store's stage name: the matrices live in ``stage_dir(STAGE)``.
STAGE = "fe"
#: Modules of prs_geom.analysis.fe that use the matrices without computing them: their source
#: does not enter the key.
_NOT_COMPUTING = ("cache.py", "compliance.py")
_ARRAYS = ("matrix", "axial_position_mm", "axial_sign", "body", "local", "contacts_per_ring", "band_half_width_mm",
           "local_by_reference", "unloaded_teeth", "end_lengths_mm")
_SCALARS = ("level", "teeth", "n_dofs", "body_per_pitch", "body_per_pitch_1d", "pitch_mm", "support_z_mm", "seconds")
_PARTS = ("screw", "roller", "nut")


def require_fe() -> None:
    """Raise :class:`~prs_geom.model.errors.EnvironmentFailure` with the install command when
    the optional extra ``fe`` (scikit-fem) is missing; before any work or output."""
    import importlib

    importlib.import_module("prs_geom.analysis.fe")   # raises with the install command


def cache_dir() -> Path:
    """The folder of the cached matrices, ``stage_dir("fe")`` (:mod:`prs_geom.runtime.cache`)."""
    return stage_dir(STAGE)


def code_fingerprint() -> str:
    """SHA-256 (hex) of the source of the modules that compute the matrices and of the
    numerical libraries' versions."""
    from importlib.metadata import version

    import scipy

    import prs_geom.analysis.fe as fe

    h = hashlib.sha256()
    for path in sorted(Path(fe.__file__).parent.glob("*.py")):
        if path.name in _NOT_COMPUTING:
            continue
        h.update(path.name.encode())
        h.update(path.read_bytes())
    h.update(f"skfem {version('scikit-fem')} numpy {np.__version__} scipy {scipy.__version__}".encode())
    return h.hexdigest()


def _description(section: Any, level: int, teeth: int) -> str:
    return f"{section!r}|level={int(level)}|teeth={int(teeth)}"


def part_key(section: Any, level: int, teeth: int, fingerprint: str | None = None) -> str:
    """The cache key of one part section (module docstring), 64 hex digits; ``fingerprint``
    defaults to :func:`code_fingerprint`."""
    fp = code_fingerprint() if fingerprint is None else fingerprint
    return hashlib.sha256((_description(section, level, teeth) + "|" + fp).encode()).hexdigest()


def influence_arrays(pi: Any) -> dict[str, np.ndarray]:
    """A :class:`~prs_geom.analysis.fe.teeth.PartInfluence` as named arrays (0-d for scalars
    and names) for the store."""
    return {"part": np.array(pi.part), "flanks": np.array(list(pi.flanks)),
            "support_face": np.array(pi.support_face), **{k: np.asarray(getattr(pi, k)) for k in _ARRAYS},
            **{k: np.array(getattr(pi, k)) for k in _SCALARS}}


def influence_from_arrays(arrays: dict[str, np.ndarray]) -> Any:
    """The :class:`~prs_geom.analysis.fe.teeth.PartInfluence` of :func:`influence_arrays`' output."""
    from prs_geom.analysis.fe.teeth import PartInfluence

    fields: dict[str, Any] = {k: arrays[k] for k in _ARRAYS}
    fields["unloaded_teeth"] = tuple(int(e) for e in arrays["unloaded_teeth"])
    fields["end_lengths_mm"] = tuple(float(e) for e in arrays["end_lengths_mm"])
    fields.update({k: arrays[k].item() for k in _SCALARS})
    return PartInfluence(part=str(arrays["part"]), flanks=tuple(str(f) for f in arrays["flanks"]),
                         support_face=str(arrays["support_face"]), **fields)


def _stored_influence(store: ArrayStore, name: str, key: str, description: str) -> tuple[Any, str]:
    """``(PartInfluence, "hit")`` from the store, or ``(None, status)``; an entry of another
    layout counts as unreadable."""
    arrays, status = store.read(name, key, description)
    if arrays is None:
        return None, status
    try:
        return influence_from_arrays(arrays), status
    except (KeyError, ValueError, TypeError):
        return None, "unreadable"


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
                     progress: ProgressFn = silent, folder: Path | None = None,
                     extension: int | None = None, label: str = "fe matrices") -> CachedInfluence:
    """The influence matrices of ``design`` (engaged teeth, converged level, sections
    extended by ``EXTENSION_TEETH`` by default; ``extension=0``: the sections that end at the
    engaged teeth, a separate entry), read from the cache (``folder``, default
    :func:`cache_dir`) where present, else computed part by part and stored.

    ``progress(label, parts done, 3)`` after each part."""
    require_fe()
    from prs_geom.analysis.fe.teeth import (CONVERGED_LEVEL, EXTENSION_TEETH, InfluenceMatrices, part_influence,
                                            part_sections)

    started = time.perf_counter()
    level = CONVERGED_LEVEL if level is None else int(level)
    teeth = design.thread.engaged_teeth if teeth is None else int(teeth)
    store = ArrayStore(cache_dir() if folder is None else Path(folder))
    sections = part_sections(design, contact, EXTENSION_TEETH if extension is None else int(extension))
    fingerprint = code_fingerprint()
    parts, hits, keys, stored, warnings = {}, {}, {}, True, []
    progress(label, 0, len(_PARTS))
    for done, name in enumerate(_PARTS, start=1):
        description = _description(sections[name], level, teeth)
        key = keys[name] = part_key(sections[name], level, teeth, fingerprint)
        pi, status = _stored_influence(store, name, key, description)
        hits[name] = pi is not None
        if status == "tampered":
            warnings.append(f"the cached {name} influence matrix {store.path(name, key)} does not match its "
                            f"checksum (changed since prs-geom wrote it): not used; recomputed and replaced")
        if pi is None:
            pi = part_influence(sections[name], level, teeth)
            stored = store.write(name, key, description, influence_arrays(pi)) and stored
        parts[name] = pi
        progress(label, done, len(_PARTS))
    return CachedInfluence(influence=InfluenceMatrices(**parts), hits=hits,
                           keys=keys, folder=store.folder, stored=stored, seconds=time.perf_counter() - started,
                           warnings=tuple(warnings))
