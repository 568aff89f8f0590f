"""Worker processes end when the process that started them dies, whatever the signal.

A sweep's main process can be killed with SIGKILL (out-of-memory killer, a batch
system, ``kill -9``), which runs none of its clean-up: without this, the local
pool's workers (about 200 MB each) would run on, orphaned. Two mechanisms, both
set up in the worker at start:

- Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` makes the kernel kill the worker the
  moment its parent exits (immediate, even inside a Numba kernel holding the GIL);
- everywhere: a daemon thread that checks every ``POLL_S`` seconds whether the
  worker was re-parented and then exits the process (the fallback where prctl is
  missing; it waits for the GIL, so it acts between runs).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import logging
import os
import signal
import sys
import threading
import time

__all__ = ["POLL_S", "tie_to_parent"]

log = logging.getLogger(__name__)

POLL_S = 1.0
_PR_SET_PDEATHSIG = 1


def _set_pdeathsig() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        return libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def _watch(parent_pid: int) -> None:
    while True:
        if os.getppid() != parent_pid:
            os._exit(1)  # orphaned: no clean-up is owed to a parent that is gone
        time.sleep(POLL_S)


def tie_to_parent(parent_pid: int) -> None:
    """Make this process exit when ``parent_pid`` (its parent) dies.

    Parameters
    ----------
    parent_pid : int
        PID of the process that started this one, as that process saw itself
        (``os.getpid()`` there): compared with ``os.getppid()`` here, so a parent
        that died before this call is caught too.
    """
    if os.getppid() != parent_pid:
        os._exit(1)
    armed = _set_pdeathsig()
    if os.getppid() != parent_pid:  # died between the check and prctl
        os._exit(1)
    threading.Thread(target=_watch, args=(parent_pid,), name="lifeline", daemon=True).start()
    log.debug("tied to parent %d (pdeathsig %s)", parent_pid, "on" if armed else "unavailable")
