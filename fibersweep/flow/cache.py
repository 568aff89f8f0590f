"""Content-addressed on-disk cache of flow fields.

Layout: ``<cache_dir>/flow-<key>/`` holds ``ux.npy``, ``uy.npy``, ``solid.npy``
(and ``u3d.npy`` if kept), ``meta.json`` and, written last, ``manifest.json``
with the sha256 of every file. The directory is assembled under a temporary
name and renamed into place (atomic on one file system), so a reader sees a
complete entry or none. An entry whose manifest is missing or whose checksums
do not match is treated as absent: it is moved aside and recomputed. Velocity
arrays are opened memory-mapped, read-only.
"""

from __future__ import annotations

import copy
import hashlib
import json
import logging
import os
import shutil
import tempfile
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cell import CELL_SOLVER_VERSION
from fibersweep.flow.cell_cache import cell_path, get_cell_field
from fibersweep.flow.field import FlowField
from fibersweep.flow.ghost import GHOST_METHOD, extend_into_wall
from fibersweep.flow.patch import PATCH_METHOD
from fibersweep.flow.schemes import get_wall_scheme
from fibersweep.flow.solver import SOLVER_VERSION, solve_flow

__all__ = [
    "CacheInfo",
    "cache_key",
    "entry_complete",
    "get_flow_field",
    "load_entry",
    "CorruptCacheError",
]

log = logging.getLogger(__name__)

MANIFEST = "manifest.json"
ARRAYS = ("ux", "uy", "solid")


class CorruptCacheError(Exception):
    """A cache entry is incomplete or fails its checksum (internal: triggers recompute)."""


@dataclass(frozen=True)
class CacheInfo:
    """Where a field came from and what the solver reported.

    Attributes
    ----------
    key : str
        Content hash of the settings and solver version.
    path : Path
        Entry directory.
    hit : bool
        True if loaded from the cache, False if computed now.
    steps, converged, residual, seconds :
        Solver report of the run that produced the entry: steps on the final
        grid, convergence there, and the seconds of the whole solve.
    u_center_reached : float
        Midplane centreline speed far from the pillar in the stored field [µm/s].
    grid : tuple of int
        (nx, ny, nz solved, nz full depth).
    coarse_steps : int
        Steps spent on coarser grids for the initial guess (nested solve).
    """

    key: str
    path: Path
    hit: bool
    steps: int
    converged: bool
    residual: float
    seconds: float
    u_center_reached: float
    grid: tuple[int, ...]
    coarse_steps: int = 0


# Settings added after fields were cached, with the value that reproduces what was
# computed before they existed: at that value they stay out of the key, so those
# fields keep their keys (and stored sweeps compare equal, see key_settings).
GEOMETRY_ADDED = {"pillar_shape": "triangle", "pillar_rotation": 0.0, "pillar_vertices": None}
FLOW_ADDED = {"precision": "float32", "patch": None}


def key_settings(flow: dict[str, Any]) -> dict[str, Any]:
    """Flow settings as JSON (``FlowSettings.model_dump(mode="json")``, or a stored
    manifest's, which may predate some keys) as they enter the cache key.

    Keys added later are dropped at the value that reproduces older fields (the
    pillar-shape keys only together, for the unrotated triangle), so a settings
    dump from before they existed and one from now compare equal.
    """
    out = copy.deepcopy(flow)
    geometry = out.get("geometry")
    if isinstance(geometry, dict) and all(
        geometry.get(k, v) == v for k, v in GEOMETRY_ADDED.items()
    ):
        for k in GEOMETRY_ADDED:
            geometry.pop(k, None)
    for k, v in FLOW_ADDED.items():
        if out.get(k, v) == v:
            out.pop(k, None)
    return out


def cache_key(settings: FlowSettings) -> str:
    """sha256 (hex, 24 chars) of every setting plus the solver version.

    Settings added after fields were first cached enter only away from the value
    that reproduces those fields (:func:`key_settings`), so they keep their keys.
    """
    payload = {"settings": key_settings(settings.model_dump(mode="json")), "solver": SOLVER_VERSION}
    if settings.patch is not None:  # the nesting's version (a field without a patch: no key)
        payload["patch_method"] = PATCH_METHOD
    if settings.array is not None:  # the unit cell's solver (a channel: no key)
        payload["cell_solver"] = CELL_SOLVER_VERSION
    blob = json.dumps(payload, sort_keys=True, separators=(",", ":")).encode()
    return hashlib.sha256(blob).hexdigest()[:24]


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _write_entry(field: FlowField, key: str, tmp: Path) -> None:
    files = {"ux": field.ux, "uy": field.uy, "solid": field.solid}
    if field.u3d is not None:
        files["u3d"] = field.u3d
    sums = {}
    for name, arr in files.items():
        p = tmp / f"{name}.npy"
        np.save(p, np.ascontiguousarray(arr))
        sums[p.name] = _sha256(p)
    meta = {**dict(field.meta), "cache_key": key}
    (tmp / "meta.json").write_text(json.dumps(meta, indent=1, sort_keys=True))
    sums["meta.json"] = _sha256(tmp / "meta.json")
    (tmp / MANIFEST).write_text(json.dumps({"key": key, "sha256": sums}, indent=1))
    for p in tmp.iterdir():  # flush file data before the rename makes it visible
        with open(p, "rb") as fh:
            os.fsync(fh.fileno())


def load_entry(
    path: str | Path, settings: FlowSettings, *, mmap: bool = True, verify: bool = True
) -> FlowField:
    """Open a cache entry as a FlowField.

    Raises
    ------
    CorruptCacheError
        Missing manifest or file, checksum mismatch, or unreadable arrays.
    """
    path = Path(path)
    try:
        manifest = json.loads((path / MANIFEST).read_text())
        sums = manifest["sha256"]
        if verify:
            for name, digest in sums.items():
                if _sha256(path / name) != digest:
                    raise CorruptCacheError(f"{path / name}: checksum mismatch")
        meta = json.loads((path / "meta.json").read_text())
        mode = "r" if mmap else None
        ux = np.load(path / "ux.npy", mmap_mode=mode)
        uy = np.load(path / "uy.npy", mmap_mode=mode)
        solid = np.load(path / "solid.npy")
        u3d = np.load(path / "u3d.npy", mmap_mode=mode) if "u3d.npy" in sums else None
    except CorruptCacheError:
        raise
    except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
        raise CorruptCacheError(f"{path}: unreadable cache entry ({exc})") from exc
    geometry = settings.geometry.to_geometry()
    sub_grid = get_wall_scheme(settings.pillar_boundary).sub_grid
    if sub_grid and meta.get("wall_ghosts") != GHOST_METHOD:
        # entry written before ghost values were stored: derive them (in memory)
        ux, uy = extend_into_wall(ux, uy, solid, geometry.shape, float(settings.field_dx))
        meta = {**meta, "wall_ghosts": GHOST_METHOD}
    return FlowField(
        ux=ux,
        uy=uy,
        dx=float(settings.field_dx),
        geometry=geometry,
        fluid=settings.fluid.to_fluid(),
        solid=solid,
        meta=meta,
        u3d=u3d,
    )


def _info(field: FlowField, key: str, path: Path, hit: bool) -> CacheInfo:
    rep = field.meta["report"]
    return CacheInfo(
        key=key,
        path=path,
        hit=hit,
        steps=int(rep["steps"]),
        converged=bool(rep["converged"]),
        residual=float(rep["residual"]),
        seconds=float(rep["seconds"]) + float(rep.get("coarse_seconds", 0.0)),
        u_center_reached=float(field.meta["u_center_reached"]),
        grid=tuple(int(v) for v in rep["grid"]),
        coarse_steps=int(rep.get("coarse_steps", 0)),
    )


def _discard(path: Path) -> None:
    """Move a bad entry aside atomically, then delete it."""
    trash = path.with_name(f".trash-{path.name}-{uuid.uuid4().hex[:8]}")
    try:
        os.replace(path, trash)
    except FileNotFoundError:
        return
    shutil.rmtree(trash, ignore_errors=True)


def entry_complete(settings: FlowSettings, cache_dir: str | Path) -> bool:
    """Whether the cache holds a complete entry for ``settings`` (computes nothing)."""
    key = cache_key(settings)
    if settings.array is not None:
        return (Path(cache_dir) / f"cell-{key}.npz").exists()
    # A complete channel entry is flow-<key>/ with its manifest written last.
    return (Path(cache_dir) / f"flow-{key}" / MANIFEST).exists()


def _cell_info(field: Any, key: str, path: Path, hit: bool) -> CacheInfo:
    m = field.meta
    return CacheInfo(
        key=key,
        path=path,
        hit=hit,
        steps=int(m["steps"]),
        converged=bool(m["converged"]),
        residual=float(m["residual"]),
        seconds=float(m["seconds"]),
        u_center_reached=float(field.u_center),
        grid=tuple(int(v) for v in m["grid"]),
    )


def get_flow_field(
    settings: FlowSettings, cache_dir: str | Path, *, force: bool = False, mmap: bool = True
) -> tuple[Any, CacheInfo]:
    """The flow field for ``settings``, from the cache or computed and stored.

    Parameters
    ----------
    settings : FlowSettings
    cache_dir : str or Path
        Cache root (created if missing).
    force : bool
        Recompute and replace the entry even if a valid one exists.
    mmap : bool
        Open ux, uy memory-mapped read-only (for worker processes).

    Returns
    -------
    (FlowField, CacheInfo)
        With ``settings.array`` set: the unit cell's
        :class:`~fibersweep.flow.cell.CellField` (entry ``cell-<key>.npz``,
        :mod:`fibersweep.flow.cell_cache`).
    """
    root = Path(cache_dir)
    root.mkdir(parents=True, exist_ok=True)
    key = cache_key(settings)
    if settings.array is not None:
        cell, hit = get_cell_field(settings, root, key, force=force)
        return cell, _cell_info(cell, key, cell_path(root, key), hit)
    path = root / f"flow-{key}"
    if path.exists() and not force:
        try:
            field = load_entry(path, settings, mmap=mmap)
            log.info("flow cache hit %s", path)
            return field, _info(field, key, path, hit=True)
        except CorruptCacheError as exc:
            log.warning("discarding corrupt flow cache entry: %s", exc)
            _discard(path)
    field = solve_flow(settings)
    tmp = Path(tempfile.mkdtemp(prefix=f".tmp-flow-{key}-", dir=root))
    try:
        _write_entry(field, key, tmp)
        os.chmod(tmp, 0o755)  # mkdtemp creates 0700
        if path.exists():
            _discard(path)  # force, or a corrupt entry written meanwhile
        try:
            os.replace(tmp, path)
        except OSError:
            # another process installed the same key first: keep theirs if it is valid
            try:
                load_entry(path, settings, mmap=mmap)
            except CorruptCacheError:
                _discard(path)
                os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
    stored = load_entry(path, settings, mmap=mmap, verify=False)
    log.info("flow cache miss: computed and stored %s", path)
    return stored, _info(stored, key, path, hit=False)
