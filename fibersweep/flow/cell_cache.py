"""Content-addressed cache of unit-cell fields (``flow.array``): one ``cell-<key>.npz`` each.

The key is the flow cache key (:func:`fibersweep.flow.cache.cache_key`, which
adds the cell solver's version when ``flow.array`` is set). A field is solved
once (:func:`fibersweep.flow.cell.solve_cell`), scaled (:func:`~fibersweep.flow.cell.field_of`)
and written atomically, with its full-depth field if ``flow.keep_3d``; an
unreadable entry is discarded and solved again.
"""

from __future__ import annotations

import io
import json
import logging
import zipfile
from pathlib import Path

import numpy as np

from fibersweep.atomic import atomic_write
from fibersweep.config.array import ArraySettings
from fibersweep.config.flow import FlowSettings
from fibersweep.flow.cell import CellField, field_of, solve_cell

__all__ = ["cell_path", "get_cell_field", "load_cell_field", "save_cell_field"]

log = logging.getLogger(__name__)


def cell_path(cache_dir: str | Path, key: str) -> Path:
    """The cache entry of a unit-cell field."""
    return Path(cache_dir) / f"cell-{key}.npz"


def save_cell_field(field: CellField, path: str | Path) -> None:
    """Write a cell field as .npz, atomically (a reader sees all of it or nothing)."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    arrays = {} if field.u3d is None else {"u3d": field.u3d}
    np.savez(buf, ux=field.ux, uy=field.uy, dx=field.dx, meta=json.dumps(field.meta), **arrays)
    atomic_write(path, buf.getvalue())


def load_cell_field(path: str | Path) -> CellField:
    """A cell field written by :func:`save_cell_field` (its array from the stored settings).

    Raises
    ------
    OSError, ValueError, KeyError
        A missing or unreadable entry.
    """
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        array = ArraySettings.model_validate(meta["settings"]["array"]).to_array()
        u3d = z["u3d"] if "u3d" in z.files else None
        return CellField(array, z["ux"], z["uy"], float(z["dx"]), meta, u3d)


def get_cell_field(
    settings: FlowSettings, cache_dir: str | Path, key: str, *, force: bool = False
) -> tuple[CellField, bool]:
    """The unit-cell field of ``settings`` (a FlowSettings with ``array``): cached or solved.

    Returns
    -------
    (CellField, bool)
        The field [µm/s] and whether it came from the cache.
    """
    path = cell_path(cache_dir, key)
    if path.exists() and not force:
        try:
            field = load_cell_field(path)
            log.info("cell cache hit %s", path)
            return field, True
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
            log.warning("discarding unreadable cell cache entry %s: %s", path, exc)
            path.unlink(missing_ok=True)
    field = field_of(settings, solve_cell(settings))
    field.meta["cache_key"] = key
    save_cell_field(field, path)
    log.info("cell cache miss: solved and stored %s", path)
    return field, False
