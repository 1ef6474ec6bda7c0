"""Output folders that never lose a user's files.

Rule (docs/cli.md "Output folders")
------------------------------
prs-geom marks every folder it writes with a manifest, :data:`MANIFEST_NAME`, listing
the files it wrote and the version that wrote them. An output path may be

* a path that does not exist yet (its parent folders are created),
* an empty folder, or
* a folder carrying that manifest and nothing else than the files its manifest lists,
  each of them as prs-geom wrote it.

Ownership is by content: the manifest (format 2) records the SHA-256 of every file written.
A file whose content changed since (a line added to ``parts_list.csv`` by hand) is the
user's now, and a build that would replace it is refused naming the file, unless it is
given ``force`` (``--force``). A folder with a manifest of format 1 (names only) is
rebuilt once, with a warning (:func:`legacy_manifest`). The design file a build reads may
lie inside its own output folder: that file is exempt from the check (``keep``) and the
new folder holds it byte for byte as it was (:class:`AtomicOutputDir`).

Anything else is refused before any work starts (:class:`OutputRefused`, exit code 2),
naming the path and what is in the way; nothing is touched. A file given where a folder
is expected is refused the same way, and so is the current working directory (replacing
the folder a shell stands in would leave the shell in a deleted folder).

Writing is atomic: everything goes into a temporary sibling folder
``.<name>.tmp-<pid>-<random>`` that carries the manifest (marked in progress) from its
first moment. Only when every stage has succeeded is an existing output renamed aside to
``.<name>.old-<pid>-<random>``, the new folder renamed into place, and the old one
removed last. On an exception (including Ctrl-C and SIGTERM, which the CLI turns into
exceptions) the temporary folder is removed and the target is as it was.

A process killed outright (SIGKILL, power loss) cannot clean up; its temporary folders
carry its pid, and the next run that writes beside them removes those whose process is
gone (only folders that carry the prs-geom manifest). An ``.old-`` folder whose target
is missing (killed between the two renames) is put back in place instead of removed.
"""
from __future__ import annotations

import json
import os
import re
import secrets
import shutil
import signal
import time
from pathlib import Path
from types import TracebackType
from typing import Any, Iterable

from prs_geom.model.errors import OutputRefused
from prs_geom.model.io import check_output_file, is_office_lock, read_user_file, write_file_atomic

__all__ = ["MANIFEST_NAME", "AtomicOutputDir", "OutputRefused", "check_output_dir", "check_output_file",
           "clean_stale", "file_sha256", "legacy_manifest", "read_manifest", "write_file_atomic"]

#: Name of the manifest that marks a folder as written by prs-geom.
MANIFEST_NAME = ".prs-geom-manifest.json"
#: 1: names only; 2: names and the SHA-256 of each file (``sha256``).
MANIFEST_FORMAT = 2
#: Temporary and set-aside folders: .<target>.tmp-<pid>-<hex> and .<target>.old-<pid>-<hex>.
_TEMP_RE = re.compile(r"^\.(?P<target>.+)\.(?P<kind>tmp|old)-(?P<pid>\d+)-[0-9a-f]{8}$")


def read_manifest(folder: Path) -> dict[str, Any] | None:
    """The manifest of ``folder``, or None when it has none (or an unreadable one)."""
    try:
        data = json.loads((folder / MANIFEST_NAME).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("written_by") != "prs-geom" or \
            not isinstance(data.get("files"), list):
        return None
    return data


#: file_sha256's results by (path, device, inode, size, mtime in ns): a build checks the
#: folder it replaces up to three times (the command, entering and leaving the temporary
#: folder), and a file whose identity, size and time did not change is not read again
_HASHED: dict[tuple[str, int, int, int, int], str] = {}


def file_sha256(path: Path) -> str:
    """SHA-256 of a file's bytes, hex (:func:`prs_geom.runtime.cache.file_sha256`, once per
    file identity, size and time in a process)."""
    from prs_geom.runtime.cache import file_sha256 as sha256_of

    st = os.stat(path)
    ident = (str(path), st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns)
    if ident not in _HASHED:
        if len(_HASHED) > 4096:
            _HASHED.clear()
        _HASHED[ident] = sha256_of(path)
    return _HASHED[ident]


def legacy_manifest(folder: str | os.PathLike[str]) -> bool:
    """Whether ``folder`` carries a prs-geom manifest without content hashes (format 1):
    such a folder is rebuilt once without the content check, which the caller announces."""
    manifest = read_manifest(Path(folder))
    return manifest is not None and not isinstance(manifest.get("sha256"), dict)


def _with_parents(names: set[str]) -> set[str]:
    """``names`` and every folder that holds one of them (POSIX relative paths)."""
    out = set(names)
    for f in names:
        parts = f.split("/")
        out.update("/".join(parts[:k]) for k in range(1, len(parts)))
    return out


def _entries(folder: Path) -> list[str]:
    """Every file and folder below ``folder``, as POSIX paths relative to it."""
    out = []
    for root, dirs, files in os.walk(folder):
        rel = Path(root).relative_to(folder)
        for name in dirs + files:
            out.append((rel / name).as_posix())
    return sorted(out)


def _describe(names: Iterable[str], limit: int = 5) -> str:
    names = list(names)
    shown = []
    for n in names[:limit]:
        base = n.rsplit("/", 1)[-1]
        shown.append(f"{n} (lock file of a document open in an office program: close it first)"
                     if is_office_lock(base) else n)
    more = f" and {len(names) - limit} more" if len(names) > limit else ""
    return ", ".join(shown) + more


def check_output_dir(target: str | os.PathLike[str], force: bool = False, keep: Iterable[str] = ()) -> Path:
    """Check that prs-geom may (re)write ``target``; return it resolved.

    ``force`` lets a build replace listed files whose content changed since prs-geom wrote
    them; ``keep`` names files (relative POSIX paths) exempt from that check: the design
    file the build reads from inside the folder. Raises :class:`OutputRefused` naming the
    path and what is in the way.
    """
    given = str(target)
    # before resolving: resolve() follows a dangling link to its missing target, which
    # would then be created wherever the link points
    if Path(target).is_symlink() and not Path(target).exists():
        raise OutputRefused(f"output path {given!r} is a dangling symbolic link (to "
                            f"{os.readlink(target)!r}): prs-geom does not follow it; give a folder")
    path = Path(target).resolve()
    cwd = Path.cwd().resolve()
    if path == cwd or path in cwd.parents:
        raise OutputRefused(f"output folder {given!r} is the current folder or contains it: prs-geom "
                            f"replaces its output folder as a whole, so give a new or prs-geom-written "
                            f"sub-folder (for example exports/<name>)")
    if path.parent == path:
        raise OutputRefused(f"output folder {given!r} is a file-system root")
    if not path.exists():
        return path
    if not path.is_dir():
        raise OutputRefused(f"output path {given!r} is an existing file, not a folder: prs-geom does "
                            f"not replace files it did not write; give a folder")
    # the design file a build reads from inside the folder is the user's and stays there
    keep = set(keep)
    kept = _with_parents(keep)
    entries = [e for e in _entries(path) if e not in kept]
    if not entries:
        return path
    manifest = read_manifest(path)
    if manifest is None:
        raise OutputRefused(f"output folder {given!r} is not empty and was not written by prs-geom "
                            f"(no {MANIFEST_NAME}); in the way: {_describe(entries)}. Nothing was "
                            f"touched: give a new or empty folder")
    listed = _with_parents(set(manifest["files"]) | {MANIFEST_NAME})
    foreign = [e for e in entries if e not in listed]
    if foreign:
        raise OutputRefused(f"output folder {given!r} was written by prs-geom but now also holds "
                            f"files it did not write: {_describe(foreign)}. Nothing was touched: move "
                            f"them out or give another folder")
    hashes = manifest.get("sha256")
    if isinstance(hashes, dict) and not force:
        edited = [name for name in manifest["files"]
                  if name not in keep and (path / name).is_file() and hashes.get(name) != file_sha256(path / name)]
        if edited:
            raise OutputRefused(f"output folder {given!r}: {_describe(edited)} changed since prs-geom wrote "
                                f"{'it' if len(edited) == 1 else 'them'}; a build would replace "
                                f"{'it' if len(edited) == 1 else 'them'}. Nothing was touched: copy your "
                                f"changes elsewhere, or give --force to replace them")
    return path


def _pid_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    return True


def clean_stale(parent: Path) -> list[str]:
    """Remove the temporary folders of dead prs-geom processes in ``parent``.

    Only folders named like ours *and* carrying our manifest are touched. An ``.old-``
    folder whose target is missing is renamed back into place. Returns what was done.
    """
    done = []
    try:
        names = os.listdir(parent)
    except OSError:
        return done
    for name in names:
        m = _TEMP_RE.match(name)
        if not m or _pid_alive(int(m["pid"])):
            continue
        folder = parent / name
        if not folder.is_dir() or folder.is_symlink() or read_manifest(folder) is None:
            continue
        target = parent / m["target"]
        if m["kind"] == "old" and not target.exists():
            os.replace(folder, target)
            done.append(f"restored {target} from {name}")
        else:
            shutil.rmtree(folder, ignore_errors=True)
            done.append(f"removed {name}")
    return done


def _manifest(files: list[str], complete: bool, extra: dict[str, Any], hashes: dict[str, str] | None = None) -> str:
    from prs_geom._version import __version__

    data = {"written_by": "prs-geom", "format_version": MANIFEST_FORMAT, "prs_geom_version": __version__,
            "complete": complete, "pid": os.getpid(),
            "written_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **extra,
            "files": sorted(files), "sha256": dict(sorted((hashes or {}).items()))}
    return json.dumps(data, indent=2) + "\n"


class AtomicOutputDir:
    """Context manager yielding a temporary folder that replaces ``target`` on success.

    The target is checked first (:func:`check_output_dir`); stale temporary folders of dead
    processes beside it are cleaned. On success the manifest lists every file in the
    folder. On an exception inside the block the temporary folder is removed and
    ``target`` is untouched.
    """

    def __init__(self, target: str | os.PathLike[str], manifest_extra: dict[str, Any] | None = None,
                 force: bool = False, source: str | os.PathLike[str] | None = None) -> None:
        self.given = str(target)
        self.force = force
        self.target = Path(target).resolve()
        #: the input file when it lies inside the target: kept byte for byte (module doc)
        self.keep: dict[str, bytes] = {}
        if source is not None:
            src = Path(source).resolve()
            if self.target in src.parents and src.is_file():
                # bounded like every read of a user's file (model.io.read_user_file)
                self.keep[src.relative_to(self.target).as_posix()] = read_user_file(src, "design file")
        self.target = check_output_dir(target, force, self.keep)
        self.extra = dict(manifest_extra or {})
        #: SHA-256 of files whose content the writer knows (copied from a verified cache
        #: blob, or hashed for the cache already): the manifest takes them as they are
        self.known_sha256: dict[str, str] = {}
        self.tmp: Path | None = None
        self.cleaned: list[str] = []

    def __enter__(self) -> Path:
        parent = self.target.parent
        parent.mkdir(parents=True, exist_ok=True)
        self.cleaned = clean_stale(parent)
        tmp = parent / f".{self.target.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}"
        umask = os.umask(0)
        os.umask(umask)
        # Ctrl-C or SIGTERM between the mkdir and the return would leave the folder behind
        # (__exit__ does not run for an exception raised in __enter__): hold the signals
        # until the folder carries its manifest, then let a pending one in where it is
        # cleaned up.
        blocked = {signal.SIGINT, signal.SIGTERM}
        previous = signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
        try:
            tmp.mkdir(mode=0o777 & ~umask)
            self.tmp = tmp
            (tmp / MANIFEST_NAME).write_text(_manifest([], False, self.extra), encoding="utf-8")
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)
            raise
        try:
            signal.pthread_sigmask(signal.SIG_SETMASK, previous)
        except BaseException:
            shutil.rmtree(tmp, ignore_errors=True)
            raise
        return tmp

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> bool:
        assert self.tmp is not None
        if exc_type is not None:
            shutil.rmtree(self.tmp, ignore_errors=True)
            return False
        try:
            for name, data in self.keep.items():
                # the design file read from inside the folder stays as the user wrote it
                (self.tmp / name).parent.mkdir(parents=True, exist_ok=True)
                (self.tmp / name).write_bytes(data)
            files = [e for e in _entries(self.tmp) if (self.tmp / e).is_file() and e != MANIFEST_NAME]
            hashes = {f: (None if f in self.keep else self.known_sha256.get(f)) or file_sha256(self.tmp / f)
                      for f in files}
            (self.tmp / MANIFEST_NAME).write_text(_manifest(files, True, self.extra, hashes), encoding="utf-8")
            # the target may have changed while we worked: check again right before replacing
            check_output_dir(self.target, self.force, self.keep)
        except BaseException:
            shutil.rmtree(self.tmp, ignore_errors=True)
            raise
        old = None
        if self.target.exists():
            old = self.target.parent / f".{self.target.name}.old-{os.getpid()}-{secrets.token_hex(4)}"
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
