"""One writer per output folder: a lock file that names its holder.

``fibersweep run`` and ``fibersweep classify`` rewrite an output folder; two of
them at once would plan the same runs twice, or move each other's results away.
The lock is a file ``OUT/.fibersweep.lock`` created with ``O_CREAT | O_EXCL``
(atomic, also on NFS v3+) holding the holder's host, PID, command and start
time. A second writer stops at once with that information (an input problem:
exit code 2). A lock left by a process that died (same host, PID gone) is stale
and taken over; a lock from another host cannot be checked from here and is
reported with the path to remove if that host's process is known to be gone.
"""

from __future__ import annotations

import json
import logging
import os
import socket
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from pathlib import Path

from fibersweep.errors import InputError

__all__ = ["LOCK_FILE", "FolderLocked", "LockHolder", "lock_holder", "output_lock"]

log = logging.getLogger(__name__)

LOCK_FILE = ".fibersweep.lock"


class FolderLocked(InputError):
    """Another live process holds the output folder's lock."""


@dataclass(frozen=True)
class LockHolder:
    """Who holds a lock.

    Attributes
    ----------
    host : str
    pid : int
    command : str
        What the holder is doing ('run', 'classify').
    started : str
        UTC time the lock was taken (ISO 8601).
    """

    host: str
    pid: int
    command: str
    started: str

    def alive(self) -> bool | None:
        """True/False on this host; None when the holder is on another host."""
        if self.host != socket.gethostname():
            return None
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return False
        except PermissionError:  # exists, owned by someone else
            return True
        return True

    def describe(self) -> str:
        return f"`fibersweep {self.command}` (PID {self.pid} on {self.host}, since {self.started})"


def lock_holder(out: Path) -> LockHolder | None:
    """The holder recorded in ``out``'s lock file, or None when unlocked or unreadable."""
    try:
        data = json.loads((Path(out) / LOCK_FILE).read_text())
        return LockHolder(
            str(data["host"]), int(data["pid"]), str(data["command"]), str(data["started"])
        )
    except (OSError, ValueError, KeyError, TypeError):
        return None


def _try_create(path: Path, me: LockHolder) -> bool:
    try:
        fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return False
    with os.fdopen(fd, "w") as fh:
        json.dump(asdict(me), fh)
        fh.flush()
        os.fsync(fh.fileno())
    return True


@contextmanager
def output_lock(out: Path, command: str) -> Iterator[LockHolder]:
    """Hold ``out``'s lock for the ``with`` block (the folder is created if needed).

    Raises
    ------
    FolderLocked
        A live process (or one on another host) holds it; the message names it.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_FILE
    me = LockHolder(
        socket.gethostname(),
        os.getpid(),
        command,
        time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
    )
    for _ in range(3):
        if _try_create(path, me):
            break
        holder = lock_holder(out)
        if holder is None:
            # Being written this very moment, or garbage: look again before judging.
            time.sleep(0.2)
            holder = lock_holder(out)
        if holder is not None and holder.alive() is not False:
            where = (
                ""
                if holder.alive()
                else (
                    f" It cannot be checked from this host; if that process is gone, remove {path}."
                )
            )
            raise FolderLocked(
                f"{out} is in use by {holder.describe()}; wait for it to finish or stop it, "
                f"or write to another folder (-o).{where}"
            )
        # Stale (its process is gone) or unreadable: move it out of the way atomically,
        # so of two processes that both found it stale only one takes it over.
        stale = path.with_name(f"{LOCK_FILE}.stale-{os.getpid()}")
        try:
            os.replace(path, stale)
        except FileNotFoundError:
            continue
        stale.unlink(missing_ok=True)
        log.warning(
            "took over a stale lock of %s", holder.describe() if holder else "an unknown process"
        )
    else:
        raise FolderLocked(f"{out}: could not take the lock {path}; try again")
    try:
        yield me
    finally:
        if lock_holder(out) == me:
            path.unlink(missing_ok=True)
