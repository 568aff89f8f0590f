"""Atomic file writes: every file fibersweep writes goes through here.

A file is written to a temporary name beside its target, flushed to disk, given
the permissions a plain ``open`` would give (``0666`` less the process umask;
``mkstemp`` would leave ``0600``) and renamed over the target. ``os.replace``
is atomic on POSIX, so a reader sees the old file or the new one, never a
half-written one, whatever happens to the writer. Leftover temporary files
(a writer killed mid-write) are named ``.NAME.tmp-PID-TOKEN``; ``fibersweep
check`` reports them and the sweep store clears them.
"""

from __future__ import annotations

import os
import secrets
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

__all__ = ["TMP_GLOB", "atomic_path", "atomic_write", "file_mode"]

#: Glob matching the temporary files of :func:`atomic_path` in a folder.
TMP_GLOB = ".*.tmp-*"


def _umask() -> int:
    """The process umask, read without changing it where the OS allows."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except OSError:
        pass
    mask = os.umask(0o022)  # no way to read it without setting it: restore at once
    os.umask(mask)
    return mask


def file_mode() -> int:
    """Permission bits of a new file: ``0o666`` less the umask (e.g. ``0o644``)."""
    return 0o666 & ~_umask()


@contextmanager
def atomic_path(path: str | Path, *, fsync: bool = True) -> Iterator[Path]:
    """A temporary path to write to; on a clean exit it replaces ``path`` atomically.

    Parameters
    ----------
    path : path
        The target file. Its folder is created if missing.
    fsync : bool
        Flush the file's data to disk before the rename (on by default: a
        crash right after the rename must not leave an empty file).

    Yields
    ------
    Path
        Where to write. If the ``with`` block raises, the temporary file is
        removed and ``path`` is left as it was.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_name(f".{target.name}.tmp-{os.getpid()}-{secrets.token_hex(4)}")
    try:
        yield tmp
        if fsync:
            with open(tmp, "rb") as fh:
                os.fsync(fh.fileno())
        os.chmod(tmp, file_mode())
        os.replace(tmp, target)
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write(path: str | Path, data: str | bytes, *, fsync: bool = True) -> Path:
    """Write ``data`` (text as UTF-8, or bytes) to ``path`` atomically; returns ``path``."""
    with atomic_path(path, fsync=fsync) as tmp:
        tmp.write_bytes(data.encode() if isinstance(data, str) else data)
    return Path(path)
