"""A build stage's results on disk, so that a rebuild redoes only the stages whose inputs changed.

A *record* is what one stage of a build produced: the typed result objects it set, the
warnings it added, the files it wrote (name and bytes, in writing order) and the SVG text of
its plots. :class:`StageCache` keeps records in the runtime's keyed array store
(:mod:`prs_geom.runtime.cache`: checksummed entries, atomic writes, no pickles), under a key
the caller derives from exactly the stage's inputs; this module never interprets the key.

Results are written as a JSON tree plus numpy arrays (:func:`encode`, :func:`decode`), not
pickled, so that no code can come from the cache:

* ``None``, booleans, integers, floats (``repr``, so exact), strings: JSON values;
* lists, tuples, dicts (any keys), sets: tagged JSON nodes;
* numpy arrays and scalars: arrays of the entry (object arrays are refused);
* dataclass instances of a ``prs_geom`` module: their class path and every field (``init``
  or not), rebuilt without calling ``__init__`` (the object was validated when it was
  made); any other class is refused;
* ``trimesh.Trimesh``: its vertices and faces;
* the build's design, and any section or value object of it, which a result may hold: a
  marker with its path (``""``, ``"materials.screw"``), rebuilt as the current build's
  object at that path. A hit means the fields the stage reads are the same; a part of the
  design it only holds is then the current one, as a fresh run would hold it.

An object met twice is stored once and comes back as one object (the rollers share a mesh).
A result of any other type raises :class:`Uncacheable`: the stage then runs every time.

* Where: ``stage_dir("stages")`` (:func:`prs_geom.runtime.cache.stage_dir`), one entry
  ``<stage>-<key>.npz`` per record; the FE influence matrices live beside it in
  ``stage_dir("fe")``. At most :data:`KEEP` records per stage are kept, the least recently
  used removed first (only files of this folder named like an entry).
* A record that fails its integrity check is not used (the stage runs again, and its new
  record replaces it).
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import importlib
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from prs_geom.model.io import atomic_path
from prs_geom.runtime.cache import ArrayStore, file_sha256, stage_dir

__all__ = ["BLOB_GRACE_S", "KEEP", "STAGE", "STAGE_CACHE_ENV", "StageCache", "StageRecord", "Uncacheable", "decode",
           "enabled", "encode", "source_fingerprint"]

#: Environment variable that turns the stage cache off for builds that do not say (``0``).
STAGE_CACHE_ENV = "PRS_GEOM_STAGE_CACHE"

#: The store's folder name under the cache root.
STAGE = "stages"
#: Records kept per stage: the most recently used ones.
KEEP = 3
#: A blob no record names is removed once nobody wrote or read it for this long (s).
BLOB_GRACE_S = 600.0
#: Libraries whose version can change a stage's numbers or file bytes.
_LIBRARIES = ("numpy", "scipy", "trimesh", "manifold3d", "python-fcl", "ezdxf", "matplotlib", "openpyxl",
              "lib3mf", "scikit-fem", "cadquery-ocp")


def enabled() -> bool:
    """Whether builds use the stage cache: unless ``$PRS_GEOM_STAGE_CACHE`` is ``0`` (or
    ``off``, ``no``, ``false``)."""
    return os.environ.get(STAGE_CACHE_ENV, "1").strip().lower() not in ("0", "off", "no", "false")


class Uncacheable(TypeError):
    """A stage result holds a value the record format does not carry."""


@functools.lru_cache(maxsize=1)
def source_fingerprint() -> str:
    """SHA-256 (hex) of every file of the installed prs_geom package (source, templates,
    schemas, vendored scripts) and of the versions of the libraries that shape its outputs:
    the version string does not change with each edit, this does."""
    from importlib.metadata import PackageNotFoundError, version

    import prs_geom

    root = Path(prs_geom.__file__).parent
    h = hashlib.sha256()
    for path in sorted(p for p in root.rglob("*") if p.is_file() and "__pycache__" not in p.parts
                       and p.suffix not in (".pyc", ".pyo")):
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes())
    for lib in _LIBRARIES:
        try:
            h.update(f"{lib}={version(lib)}\0".encode())
        except PackageNotFoundError:
            h.update(f"{lib}=absent\0".encode())
    return h.hexdigest()


# --------------------------------------------------------------------------- encoding
class _Encoder:
    def __init__(self, design: Any, prefix: str) -> None:
        self.prefix = prefix
        self.design_paths = _design_paths(design)
        self.arrays: dict[str, np.ndarray] = {}
        self.seen: dict[int, int] = {}
        self.keep: list[Any] = []       # what the ids of ``seen`` belong to, alive while encoding

    def array(self, a: np.ndarray) -> str:
        if a.dtype.hasobject:
            raise Uncacheable("an object array")
        name = f"{self.prefix}{len(self.arrays)}"
        # not ascontiguousarray: it makes a 0-d array (a numpy scalar) 1-d
        self.arrays[name] = a if a.flags.c_contiguous else a.copy(order="C")
        return name

    def shared(self, obj: Any, make) -> Any:
        ref = self.seen.get(id(obj))
        if ref is not None:
            return {"ref": ref}
        ref = self.seen[id(obj)] = len(self.seen)
        self.keep.append(obj)
        return {"id": ref, **make()}

    def node(self, obj: Any) -> Any:
        if obj is None or isinstance(obj, (bool, str)) or type(obj) in (int, float):
            return obj
        path = self.design_paths.get(id(obj))
        if path is not None:
            return {"design": path}
        if isinstance(obj, np.ndarray):
            return self.shared(obj, lambda: {"array": self.array(obj)})
        if isinstance(obj, np.generic):
            return {"scalar": self.array(np.asarray(obj))}
        if isinstance(obj, (list, tuple)):
            return {"list" if isinstance(obj, list) else "tuple": [self.node(v) for v in obj]}
        if isinstance(obj, dict):
            return {"dict": [[self.node(k), self.node(v)] for k, v in obj.items()]}
        if isinstance(obj, (set, frozenset)):
            items = sorted((self.node(v) for v in obj), key=lambda n: json.dumps(n, sort_keys=True))
            return {"frozenset" if isinstance(obj, frozenset) else "set": items}
        if isinstance(obj, Path):
            return {"path": str(obj)}
        if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
            return self.shared(obj, lambda: self.dataclass(obj))
        if type(obj).__name__ == "Trimesh" and type(obj).__module__.startswith("trimesh"):
            return self.shared(obj, lambda: {"trimesh": [self.array(np.asarray(obj.vertices)),
                                                         self.array(np.asarray(obj.faces))]})
        raise Uncacheable(f"a {type(obj).__module__}.{type(obj).__qualname__}")

    def dataclass(self, obj: Any) -> dict[str, Any]:
        cls = type(obj)
        if not cls.__module__.startswith("prs_geom."):
            raise Uncacheable(f"a {cls.__module__}.{cls.__qualname__}")
        fields = {f.name: self.node(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
        return {"class": f"{cls.__module__}:{cls.__qualname__}", "fields": fields}


def _design_paths(design: Any) -> dict[int, str]:
    """id -> dotted path of the design and of every dataclass object inside it (first path
    of an object met twice)."""
    out: dict[int, str] = {}
    stack = [("", design)] if design is not None else []
    while stack:
        path, obj = stack.pop()
        if id(obj) in out:
            continue
        out[id(obj)] = path
        for f in dataclasses.fields(obj):
            value = getattr(obj, f.name)
            if dataclasses.is_dataclass(value) and not isinstance(value, type):
                stack.append((f"{path}.{f.name}" if path else f.name, value))
    return out


def encode(value: Any, design: Any = None, prefix: str = "a") -> tuple[str, dict[str, np.ndarray]]:
    """``value`` as (JSON text, arrays named ``prefix`` + a number) (module docstring);
    ``design`` is stored as a marker. Raises :class:`Uncacheable` for a value the format
    does not carry."""
    enc = _Encoder(design, prefix)
    tree = enc.node(value)
    return json.dumps(tree, allow_nan=True), enc.arrays


def _class(path: str) -> type:
    module, _, qualname = path.partition(":")
    if not module.startswith("prs_geom."):
        raise ValueError(f"a record names a class outside prs_geom: {path!r}")
    obj: Any = importlib.import_module(module)
    for part in qualname.split("."):
        obj = getattr(obj, part)
    if not (isinstance(obj, type) and dataclasses.is_dataclass(obj)):
        raise ValueError(f"a record names {path!r}, which is not a dataclass")
    return obj


class _Decoder:
    def __init__(self, arrays: dict[str, np.ndarray], design: Any) -> None:
        self.arrays, self.design = arrays, design
        self.made: dict[int, Any] = {}

    def node(self, n: Any) -> Any:
        if not isinstance(n, dict):
            return n
        if "ref" in n:
            return self.made[n["ref"]]
        if "design" in n:
            obj = self.design
            for name in filter(None, n["design"].split(".")):
                obj = getattr(obj, name)
            return obj
        if "array" in n:
            return self.keep(n, self.arrays[n["array"]])
        if "scalar" in n:
            return self.arrays[n["scalar"]][()]
        for kind, make in (("list", list), ("tuple", tuple), ("set", set), ("frozenset", frozenset)):
            if kind in n:
                return make(self.node(v) for v in n[kind])
        if "dict" in n:
            return {self.node(k): self.node(v) for k, v in n["dict"]}
        if "path" in n:
            return Path(n["path"])
        if "trimesh" in n:
            import trimesh

            v, f = (self.arrays[a] for a in n["trimesh"])
            return self.keep(n, trimesh.Trimesh(v, f, process=False, validate=False))
        if "class" in n:
            cls = _class(n["class"])
            obj = object.__new__(cls)
            self.keep(n, obj)
            for name, value in n["fields"].items():
                object.__setattr__(obj, name, self.node(value))
            return obj
        raise ValueError(f"a record holds an unknown node {sorted(n)}")

    def keep(self, n: dict[str, Any], obj: Any) -> Any:
        self.made[n["id"]] = obj
        return obj


def decode(tree: str, arrays: dict[str, np.ndarray], design: Any = None) -> Any:
    """The value :func:`encode` wrote, with ``design`` where the encoded one was."""
    return _Decoder(arrays, design).node(json.loads(tree))


# --------------------------------------------------------------------------- records
@dataclass(frozen=True)
class StageRecord:
    """What one stage of a build produced.

    Attributes
    ----------
    results : dict
        The build-result fields the stage set, by name.
    warnings : tuple of str
        The warnings it added, in order.
    files : tuple of (str, str)
        The files it wrote, in writing order: output-relative name and the SHA-256 (hex) of
        the content, which the cache keeps once as a blob (:meth:`StageCache.blob`).
    svgs : dict
        The SVG text of its plots, by plot name.
    """

    results: dict[str, Any]
    warnings: tuple[str, ...] = ()
    files: tuple[tuple[str, str], ...] = ()
    svgs: dict[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class StageCache:
    """The stage records of one folder (module docstring).

    A record's arrays and JSON are one entry of the keyed array store; the files it wrote
    are blobs ``blobs/<sha256>``, one per distinct content, shared by the records that
    wrote the same bytes. A record is a hit only when each of its blobs is there and
    hashes to its name.

    Attributes
    ----------
    folder : Path
        Where the records live (``stage_dir("stages")`` by default).
    """

    folder: Path = field(default_factory=lambda: stage_dir(STAGE))

    @property
    def store(self) -> ArrayStore:
        return ArrayStore(Path(self.folder))

    def blob(self, sha256: str) -> Path:
        """The file holding the content whose SHA-256 is ``sha256``."""
        return Path(self.folder) / "blobs" / sha256

    def read(self, stage: str, key: str, description: str, design: Any = None) -> tuple[StageRecord | None, str]:
        """``(record, "hit")``, or ``(None, status)`` with a status of
        :data:`prs_geom.runtime.cache.READ_STATUSES` (``"unreadable"`` also for a record
        whose contents do not decode, ``"tampered"`` for a blob missing or not matching its
        hash)."""
        arrays, status = self.store.read(stage, key, description)
        if arrays is None:
            return None, status
        try:
            files = tuple((str(name), str(sha)) for name, sha in _json(arrays.pop("files")))
            svgs = _json(arrays.pop("svgs"))
            warnings = tuple(_json(arrays.pop("warnings")))
            results = decode(arrays.pop("results").tobytes().decode("utf-8"), arrays, design)
        except (KeyError, ValueError, TypeError, AttributeError, ImportError):
            return None, "unreadable"
        for _, sha in files:
            try:
                if file_sha256(self.blob(sha)) == sha:
                    os.utime(self.blob(sha))    # in use: a concurrent build's collection spares it
                    continue
                self.blob(sha).unlink()     # ours, and wrong: the next write stores it again
            except OSError:
                pass
            return None, "tampered"
        try:    # most recently used: kept longest
            os.utime(self.store.path(stage, key))
        except OSError:
            pass
        return StageRecord(results, warnings, files, svgs), "hit"

    def write(self, stage: str, key: str, description: str, record: StageRecord, sources: dict[str, Path],
              design: Any = None) -> bool:
        """Store ``record`` under ``key`` (atomically), its files copied from ``sources``
        (name -> path, the content the record's hashes name) into blobs; then drop the
        stage's least recently used records beyond :data:`KEEP` and the blobs no record
        names. False when the folder cannot be written. Raises :class:`Uncacheable` for a
        result the format does not carry."""
        import shutil

        tree, arrays = encode(record.results, design, prefix="r")
        arrays["results"] = _utf8(tree)
        arrays["warnings"] = _utf8(json.dumps(list(record.warnings)))
        arrays["svgs"] = _utf8(json.dumps(record.svgs))
        arrays["files"] = _utf8(json.dumps([list(f) for f in record.files]))
        try:
            for name, sha in record.files:
                target = self.blob(sha)
                if target.exists():
                    os.utime(target)        # in use again: not collected for a while
                    continue
                target.parent.mkdir(parents=True, exist_ok=True)
                with atomic_path(target) as tmp:
                    shutil.copyfile(sources[name], tmp)
        except OSError:
            return False
        ok = self.store.write(stage, key, description, arrays)
        if ok and self.evict(stage):
            self.collect_blobs()
        return ok

    def evict(self, stage: str, keep: int = KEEP) -> bool:
        """Remove the least recently used records of ``stage`` beyond ``keep``; whether any was."""
        folder = Path(self.folder)
        try:
            entries = [p for p in folder.glob(f"{stage}-*.npz") if _is_entry_name(p.name, stage)]
            entries.sort(key=lambda p: p.stat().st_mtime, reverse=True)
        except OSError:
            return False
        removed = False
        for path in entries[keep:]:
            try:
                path.unlink()
                removed = True
            except OSError:
                pass
        return removed

    def collect_blobs(self, spare_s: float = BLOB_GRACE_S) -> None:
        """Remove the blobs that no record names (a record that cannot be read names none)
        and that nobody wrote or read for ``spare_s`` seconds (a build running beside this
        one may have read a record that this one just evicted, and copy its blobs soon)."""
        import time

        now = time.time()
        folder = Path(self.folder)
        named: set[str] = set()
        for path in folder.glob("*.npz"):
            try:
                with np.load(path, allow_pickle=False) as z:
                    named.update(sha for _, sha in _json(z["files"]))
            except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError):
                continue
        for path in (folder / "blobs").glob("*"):
            if len(path.name) == 64 and all(c in "0123456789abcdef" for c in path.name) and path.name not in named:
                try:
                    if now - path.stat().st_mtime < spare_s:
                        continue
                    path.unlink()
                except OSError:
                    pass


def _utf8(text: str) -> np.ndarray:
    """JSON text as an array of its UTF-8 bytes (a numpy string array holds 4 bytes a character)."""
    return np.frombuffer(text.encode("utf-8"), dtype=np.uint8)


def _json(array: np.ndarray) -> Any:
    return json.loads(array.tobytes().decode("utf-8"))


def _is_entry_name(name: str, stage: str) -> bool:
    """Whether ``name`` is ``<stage>-<32 hex>.npz``, the name of an entry this module wrote."""
    key = name[len(stage) + 1:-4]
    return len(key) == 32 and all(c in "0123456789abcdef" for c in key)
