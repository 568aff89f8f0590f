"""Keep Numba's on-disk kernel cache in step with the source it was compiled from.

Numba's ``cache=True`` checks only the source file of the cached function, not
the files of the functions it calls or inlines. The fiber integrators call into
other modules (contact forces, mobility, flow interpolation) and compile in the
kernel stages of every effect module (:mod:`fibersweep.fiber.kernel.hooks`), so after
an upgrade or an edit of one of those files a stale cached integrator would run
the old physics without a word. This module hashes every source file of the
packages with cached kernels and, when the hash differs from the one stamped
beside the cache, removes the cache files, so they are compiled again from the
current source. It runs once per process, when ``fibersweep.fiber`` or
``fibersweep.flow`` is imported, and costs a few milliseconds.

Only the in-tree cache (``__pycache__`` next to the sources) is managed; with
``NUMBA_CACHE_DIR`` set, clear that folder after changing fibersweep.
"""

from __future__ import annotations

import hashlib
import logging
import os
from pathlib import Path

__all__ = ["sources_digest", "sync_kernel_cache"]

log = logging.getLogger(__name__)

_ROOT = Path(__file__).resolve().parent
#: Packages whose Numba kernels are cached on disk and call one another.
_PACKAGES = ("fiber", "flow")
_STAMP = "kernel-sources.sha256"
_done = False


def sources_digest(root: Path = _ROOT) -> str:
    """sha256 of every ``.py`` file of the kernel packages (paths and contents)."""
    h = hashlib.sha256()
    for pkg in _PACKAGES:
        for path in sorted((root / pkg).rglob("*.py")):
            h.update(str(path.relative_to(root)).encode())
            h.update(path.read_bytes())
    return h.hexdigest()


def sync_kernel_cache(root: Path = _ROOT) -> bool:
    """Remove stale Numba cache files of the kernel packages; True if any were removed.

    Safe to call many times (works once per process) and never raises: a cache
    that cannot be checked or cleared is left to Numba.
    """
    global _done
    if _done or os.environ.get("NUMBA_CACHE_DIR"):
        return False
    _done = True
    try:
        digest = sources_digest(root)
        stamp = root / "fiber" / "__pycache__" / _STAMP
        if stamp.exists() and stamp.read_text().strip() == digest:
            return False
        removed = 0
        for pkg in _PACKAGES:
            for cache in (root / pkg).rglob("__pycache__"):
                for f in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
                    f.unlink(missing_ok=True)
                    removed += 1
        stamp.parent.mkdir(parents=True, exist_ok=True)
        tmp = stamp.with_name(f".{_STAMP}.{os.getpid()}")
        tmp.write_text(digest + "\n")
        os.replace(tmp, stamp)
    except OSError as exc:  # read-only install: Numba then caches elsewhere
        log.debug("kernel cache not checked: %s", exc)
        return False
    if removed:
        log.info("kernel sources changed: removed %d stale Numba cache files", removed)
    return removed > 0
