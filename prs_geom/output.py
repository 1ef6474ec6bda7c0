"""Atomic output folders.

Every export is written into a temporary folder beside the target; only when the whole
run has succeeded is it moved into place. A failed run therefore leaves an earlier
output folder exactly as it was, and never leaves a half-written one.
"""
from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path
from types import TracebackType


class AtomicOutputDir:
    """Context manager yielding a temporary folder that replaces ``target`` on success.

    On an exception inside the block the temporary folder is removed and ``target`` is
    untouched. On success an existing ``target`` is first renamed aside, the new folder
    renamed into place, and the old one deleted, so there is no moment without a
    complete folder at ``target`` other than between two renames.
    """

    def __init__(self, target: str | os.PathLike[str]) -> None:
        self.target = Path(target).resolve()
        self.tmp: Path | None = None

    def __enter__(self) -> Path:
        self.target.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.tmp-", dir=self.target.parent))
        # mkdtemp makes a private folder; give the result the permissions of a normal one
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(self.tmp, 0o777 & ~umask)
        return self.tmp

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> bool:
        assert self.tmp is not None
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return False
        old = None
        if self.target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{self.target.name}.old-", dir=self.target.parent))
            old.rmdir()
            os.replace(self.target, old)
        try:
            os.replace(self.tmp, self.target)
        except BaseException:
            if old is not None:
                os.replace(old, self.target)
            shutil.rmtree(self.tmp, ignore_errors=True)
            raise
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return False
