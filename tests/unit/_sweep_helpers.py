"""Real, picklable task functions for testing the sweep executors without fiber physics.

Spawned pool workers and Dask workers import this module by name (pytest puts
tests/unit on sys.path, and spawned processes inherit sys.path).
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path

_INIT: dict[str, object] = {}


@dataclass(frozen=True)
class Job:
    """A task: ``key``, a number to square, how long to take, what to do."""

    key: str
    x: float
    sleep: float = 0.0
    action: str = ""  # "", "raise", "bug", "die", "die-once:<marker path>"


def init(tag: str, log_dir: str | None = None) -> None:
    """Per-worker initializer; leaves one file per process start in ``log_dir``."""
    _INIT["tag"] = tag
    if log_dir:
        Path(log_dir, f"init-{os.getpid()}").write_text(tag)


def square(job: Job) -> dict:
    """x**2 after ``sleep`` seconds; may raise or kill its own process on purpose."""
    if job.sleep:
        time.sleep(job.sleep)
    if job.action == "raise":
        raise ValueError(f"bad job {job.key}")
    if job.action == "bug":
        from fibersweep.errors import RunBug

        raise RunBug(f"run {job.key}: TypeError in the model")
    if job.action == "die":
        os._exit(3)
    if job.action.startswith("die-once:"):
        marker = Path(job.action.split(":", 1)[1])
        try:
            fd = os.open(marker, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            pass
        else:
            os.close(fd)
            os._exit(4)
    return {
        "x2": job.x**2,
        "pid": os.getpid(),
        "tag": _INIT.get("tag"),
        "blas": {v: os.environ.get(v) for v in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")},
    }
