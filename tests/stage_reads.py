"""Which design fields each build stage reads, found by watching the design.

The test helper behind the stage cache's declarations (:data:`prs_geom.pipeline.STAGE_INPUTS`).
A build runs serially (background jobs in this process, at the stage that takes them) while
``__getattribute__`` of the design and of its section classes records every field read,
stage by stage, as a dotted path: ``"loading.axial_load_n"`` for a field of a section,
``"name"`` for a top-level value, ``"tolerances"`` when an optional section is absent.
Reads made while a design or section is hashed, compared or printed by repr (an
``lru_cache`` key) are not counted, and every ``lru_cache`` of the package is emptied before
each stage, so that a stage is charged with the fields its own computation reads, not those
a cached helper read for an earlier stage.
"""
from __future__ import annotations

import contextlib
import dataclasses
import functools
import sys
import traceback
from pathlib import Path
from typing import Any

from prs_geom.model.design import PRSDesign


def _section_classes() -> dict[type, str]:
    """Section class -> section name, from a design with every optional section present."""
    import typing

    hints = typing.get_type_hints(PRSDesign)
    out: dict[type, str] = {}
    for f in dataclasses.fields(PRSDesign):
        cls = f.metadata.get("section") or hints.get(f.name)
        if isinstance(cls, type) and dataclasses.is_dataclass(cls):
            out[cls] = f.name
    return out


def _clear_package_caches() -> None:
    for name, module in list(sys.modules.items()):
        if not name.startswith("prs_geom") or module is None:
            continue
        for value in list(vars(module).values()):
            if isinstance(value, functools._lru_cache_wrapper):
                value.cache_clear()


@contextlib.contextmanager
def watching(where: dict[str, str] | None = None) -> Any:
    """Yield a set that collects the dotted paths of the design fields read meanwhile (and,
    in ``where``, the stack of each path's first read)."""
    seen: set[str] = set()
    quiet = [0]
    get = object.__getattribute__
    sections = _section_classes()
    top = {f.name for f in dataclasses.fields(PRSDesign)}
    saved: list[tuple[type, str, Any]] = []

    def note(path: str) -> None:
        if where is not None and path not in seen:
            where[path] = "".join(traceback.format_stack(limit=10)[:-2])
        seen.add(path)

    def design_get(self, name):
        value = get(self, name)
        if name in top and not quiet[0] and type(value) not in sections:
            note(name)      # a top-level value, or an absent optional section
        return value

    def section_get(section, fields):
        def getattribute(self, name):
            if name in fields and not quiet[0]:
                note(f"{section}.{name}")
            return get(self, name)
        return getattribute

    def hushed(fn):
        def inner(*args):
            quiet[0] += 1
            try:
                return fn(*args)
            finally:
                quiet[0] -= 1
        return inner

    def patch(cls, name, value):
        saved.append((cls, name, cls.__dict__.get(name, _MISSING)))
        setattr(cls, name, value)

    patch(PRSDesign, "__getattribute__", design_get)
    for cls, section in sections.items():
        patch(cls, "__getattribute__", section_get(section, {f.name for f in dataclasses.fields(cls)}))
    for cls in (PRSDesign, *sections):
        for dunder in ("__hash__", "__eq__", "__repr__"):
            patch(cls, dunder, hushed(getattr(cls, dunder)))
    try:
        yield seen
    finally:
        for cls, name, value in reversed(saved):
            if value is _MISSING:
                delattr(cls, name)
            else:
                setattr(cls, name, value)


_MISSING = object()


def stage_reads(design: PRSDesign, out: Path, options: Any = None) -> dict[str, set[str]]:
    """Run every stage of a serial build of ``design`` into ``out`` (no stage cache) and
    return, by stage, the dotted paths of the design fields it read."""
    from prs_geom import pipeline

    reads: dict[str, set[str]] = {}

    def watched(name, fn):
        def run(ctx):
            _clear_package_caches()
            with watching() as seen:
                fn(ctx)
            reads[name] = set(seen)
        return run

    stages = [(name, watched(name, fn)) for name, fn in pipeline.STAGES]
    out.mkdir(parents=True, exist_ok=True)
    pipeline.run_stages(design, out, stages=stages, options=options, workers=0)
    return reads
