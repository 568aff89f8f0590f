"""Sweeps of fibers through a tilted pillar array: config, unit-cell fields, runs, store.

A config (``configs/array.yaml``) has the sections ``array`` (the lattice,
:class:`ArraySettings`), ``flow`` (the unit-cell solve), ``fiber`` (the
channel's :class:`~fibersweep.fiber.settings.FiberSettings`; rigid model),
``sweep`` (lengths, random starts, rows, and any array setting as an axis) and
``run``. Each combination of swept array settings is one *setting*: its cell
field is solved once and cached by content; each (setting, length) gets
``starts`` seeded random entries (lateral position uniform over the cell's
inflow, angle uniform in ``theta0``), run through ``rows`` rows. One Parquet
row per run (columns in :data:`COLUMNS`) with its thinned trajectory, so the
modes can be re-labelled (:mod:`fibersweep.analysis.modes`).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import logging
import math
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from fibersweep.config.errors import ConfigError, FieldError
from fibersweep.errors import InputError
from fibersweep.fiber.settings import FiberSettings
from fibersweep.geometry import PILLAR_SHAPES, check_shape_name
from fibersweep.geometry.array import ArrayError, PillarArray

__all__ = [
    "ArrayConfig",
    "ArraySettings",
    "COLUMNS",
    "load_array_config",
    "settings_grid",
    "cell_field",
    "run_array_sweep",
]

log = logging.getLogger(__name__)

#: Parquet columns of an array sweep (units in brackets).
COLUMNS = {
    "setting": "index of the array setting (a combination of swept array values)",
    "setting_label": "the swept values as text",
    "length": "fiber length L [µm]",
    "n_beads": "beads of the fiber",
    "start": "index of the random start within (setting, length)",
    "y0": "start lateral position of the centre in the cell [µm]",
    "theta0": "start angle [deg]",
    "status": "done | trapped | timeout | failed",
    "rows": "whole rows crossed",
    "shift_per_row": "mean lateral displacement per row [µm]",
    "migration_angle": "atan(shift_per_row / period_x) [deg]",
    "fraction": "shift_per_row / (shift * period_y): 1 follows the array, 0 the flow",
    "mode": "zigzag | displacement | wrap-and-jump | trapped | mixed",
    "wraps": "contact episodes with a turn beyond 90 deg",
    "contacts": "contact episodes (from every step, not the thinned trajectory)",
    "bridging": "steps in contact with two or more pillars at once",
    "time_on_pillars": "time in contact [s]",
    "t_end": "time of the last step [s]",
    "traj_t, traj_xc, traj_yc, traj_th, traj_contact, traj_speed": "thinned trajectory",
}


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ArraySettings(_Strict):
    """The pillar array (:class:`fibersweep.geometry.array.PillarArray`), lengths in µm."""

    pillar_shape: str = Field("triangle", description=f"one of {', '.join(PILLAR_SHAPES)}")
    pillar_size: float = Field(40.0, gt=0, description="h_obs: triangle height, circle diameter")
    pillar_rotation: float = Field(0.0, description="counter-clockwise rotation [deg]")
    pillar_vertices: tuple[tuple[float, float], ...] | None = Field(
        None, description="corners of a 'polygon' in units of pillar_size"
    )
    period_x: float = Field(80.0, gt=0, description="centre-to-centre period along the flow")
    period_y: float = Field(80.0, gt=0, description="centre-to-centre period across the flow")
    shift: float = Field(0.1, ge=0, lt=1, description="row shift epsilon (tilt atan epsilon)")
    depth: float = Field(40.0, gt=0, description="channel depth H")

    def to_array(self) -> PillarArray:
        return PillarArray(**self.model_dump())

    @field_validator("pillar_shape")
    @classmethod
    def _known_shape(cls, name: str) -> str:
        return check_shape_name(name)

    @model_validator(mode="after")
    def _valid(self) -> ArraySettings:
        try:
            self.to_array()
        except ArrayError as exc:
            raise FieldError(exc.field, str(exc)) from None
        except ValueError as exc:  # the shape's own checks (polygon vertices)
            raise FieldError("pillar_vertices", str(exc)) from None
        return self


class CellFlowSettings(_Strict):
    """The unit-cell solve (:func:`fibersweep.flow.cell.solve_cell`)."""

    dx: float = Field(4.0, gt=0, description="lattice spacing [µm]")
    pillar_boundary: Literal["interpolated", "staircase", "bfl"] = "interpolated"
    symmetry: bool = True
    tolerance: float = Field(1e-6, gt=0, lt=1)
    max_steps: int = Field(200_000, ge=1)
    mean_flow: Literal["x", "force"] = Field(
        "x",
        description="x: a lateral body force keeps the mean flow along x (as side walls do); "
        "force: body force along x only, the mean flow follows the cell's permeability",
    )
    u_center: float = Field(600.0, gt=0, description="midplane speed of the same flux [µm/s]")
    viscosity: float = Field(0.340, gt=0, description="dynamic viscosity [Pa s]")


class ArraySweepSettings(_Strict):
    """What to run."""

    length: tuple[float, ...] = Field((40.0, 80.0), min_length=1, description="lengths L [µm]")
    starts: int = Field(20, ge=1, description="random starts per (setting, length)")
    seed: int = Field(0, ge=0, description="seed of the starts")
    theta0: tuple[float, float] = Field((-10.0, 10.0), description="start angle range [deg]")
    rows: int = Field(20, ge=2, description="rows to cross")
    samples_per_row: int = Field(20, ge=4, description="trajectory samples kept per row")
    axes: dict[str, tuple[Any, ...]] = Field(
        default_factory=dict, description="array setting -> values (each a sweep axis)"
    )

    @model_validator(mode="after")
    def _axes(self) -> ArraySweepSettings:
        for k, v in self.axes.items():
            if k not in ArraySettings.model_fields:
                raise FieldError(("axes", k), f"not an array setting; valid: "
                                 f"{', '.join(ArraySettings.model_fields)}")  # fmt: skip
            if not v:
                raise FieldError(("axes", k), "needs at least one value")
        return self


class ArrayRunSettings(_Strict):
    workers: int = Field(2, ge=1)
    output: str = "results/array"
    cache_dir: str = ".fibersweep-cache"


class ArrayConfig(_Strict):
    """A whole array-sweep config."""

    array: ArraySettings = ArraySettings()
    flow: CellFlowSettings = CellFlowSettings()
    fiber: FiberSettings = FiberSettings()
    sweep: ArraySweepSettings = ArraySweepSettings()
    run: ArrayRunSettings = ArrayRunSettings()

    @model_validator(mode="after")
    def _combinations(self) -> ArrayConfig:
        if self.fiber.model != "rigid":
            raise FieldError("fiber.model", "array runs use the rigid model for now")
        from fibersweep.fiber.rows import check_array_effects

        try:
            check_array_effects(self.fiber)
        except InputError as exc:
            raise FieldError("fiber.effects", str(exc)) from None
        for label, s in settings_grid(self):
            try:
                arr = ArraySettings.model_validate(s).to_array()
                arr.check_fiber(self.fiber.bead_radius)
                arr.check_lattice(self.flow.dx)
            except ValidationError as exc:
                raise FieldError("sweep.axes", f"{label}: {exc.errors()[0]['msg']}") from None
            except ArrayError as exc:
                where = f"sweep.axes.{exc.field}" if exc.field in self.sweep.axes else (
                    f"array.{exc.field}")  # fmt: skip
                raise FieldError(where, f"{label + ': ' if label else ''}{exc}") from None
        for L in self.sweep.length:
            if L < 2 * self.fiber.bead_radius:
                raise FieldError("sweep.length", f"L = {L} µm is shorter than one bead (2a)")
        return self


def settings_grid(cfg: ArrayConfig) -> list[tuple[str, dict]]:
    """(label, array settings dict) of every combination of the swept array values."""
    base = cfg.array.model_dump()
    keys = list(cfg.sweep.axes)
    out = []
    for values in itertools.product(*(cfg.sweep.axes[k] for k in keys)):
        s = {**base, **dict(zip(keys, values, strict=True))}
        label = ", ".join(f"{k}={v}" for k, v in zip(keys, values, strict=True))
        out.append((label, s))
    return out


def load_array_config(path: str | Path, overrides=()) -> ArrayConfig:
    """Read and validate an array config (messages name each field and its line)."""
    from fibersweep.config.loading import _describe, _yaml_with_lines, apply_overrides

    p = Path(path)
    try:
        located = _yaml_with_lines(p.read_text())
    except OSError as exc:
        raise ConfigError([f"cannot read config: {exc.strerror}"], str(p)) from None
    data = located.data or {}
    if overrides:
        data = apply_overrides(data, located.lines, overrides)
    try:
        return ArrayConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError([_describe(e, located.lines) for e in exc.errors()], str(p)) from None


# ------------------------------------------------------------------ fields
def _field_key(arr: dict, flow: CellFlowSettings) -> str:
    from fibersweep.flow.cell import CELL_SOLVER_VERSION

    blob = json.dumps({"array": arr, "flow": flow.model_dump(), "v": CELL_SOLVER_VERSION},
                      sort_keys=True)  # fmt: skip
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def cell_field(arr_settings: dict, flow: CellFlowSettings, cache_dir: str | Path | None):
    """The unit-cell field of these settings, from the content-addressed cache or solved."""
    from fibersweep.flow.cell import field_of, solve_cell

    array = ArraySettings.model_validate(arr_settings).to_array()
    key = _field_key(arr_settings, flow)
    path = Path(cache_dir) / f"cell-{key}.npz" if cache_dir else None
    if path is not None and path.exists():
        return load_field(path, array)
    sol = solve_cell(array, flow.dx, boundary=flow.pillar_boundary, symmetry=flow.symmetry,
                     tolerance=flow.tolerance, max_steps=flow.max_steps,
                     mean_flow=flow.mean_flow)  # fmt: skip
    field = field_of(array, sol, flow.u_center, flow.pillar_boundary,
                     {"array": arr_settings, "flow": flow.model_dump()})  # fmt: skip
    if path is not None:
        save_field(field, path)
    return field


def save_field(field, path: str | Path) -> None:
    """Write a cell field as .npz (atomically)."""
    import io

    from fibersweep.atomic import atomic_write

    Path(path).parent.mkdir(parents=True, exist_ok=True)
    buf = io.BytesIO()
    np.savez(buf, ux=field.ux, uy=field.uy, dx=field.dx, meta=json.dumps(field.meta))
    atomic_write(path, buf.getvalue())


def load_field(path: str | Path, array: PillarArray):
    """A cell field written by :func:`save_field`."""
    from fibersweep.flow.cell import CellField

    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        return CellField(array, z["ux"], z["uy"], float(z["dx"]), meta)


# ------------------------------------------------------------------ runs
def _n_beads(length: float, a: float) -> int:
    return max(1, int(round(length / (2.0 * a))))


def draw_starts(cfg: ArrayConfig, setting: int, li: int, array: PillarArray, pillar,
                n_beads: int) -> list[tuple[float, float]]:  # fmt: skip
    """Seeded random starts (y0 [µm], θ0 [deg]) in the middle of the row gap upstream of row 0.

    y0 uniform over the cell's inflow [0, λy), θ0 uniform in ``sweep.theta0``;
    a start whose beads would touch a pillar (closer than the contact cutoff)
    is drawn again. Reproducible: the generator is seeded by (seed, setting, length).
    """
    from fibersweep.fiber.mobility import fiber_offsets

    rng = np.random.default_rng([cfg.sweep.seed, setting, li])
    s = fiber_offsets(n_beads, cfg.fiber.bead_radius)
    x0 = _start_x(array)
    lo, hi = cfg.sweep.theta0
    out = []
    tries = 0
    while len(out) < cfg.sweep.starts:
        tries += 1
        if tries > 1000 * cfg.sweep.starts:
            raise InputError(f"sweep.length: no start of a {n_beads}-bead fiber clears the "
                             "pillars; shorten it or widen the gaps")  # fmt: skip
        y0 = float(rng.uniform(0.0, array.period_y))
        th = float(rng.uniform(lo, hi))
        bx = x0 + s * math.cos(math.radians(th))
        by = y0 + s * math.sin(math.radians(th))
        clear = all(
            float(np.min(sh.signed_distance(bx, by))) > pillar.r_cut
            for _, _, sh in array.images(bx.min(), by.min(), bx.max(), by.max(), pillar.r_cut)
        )
        if clear:
            out.append((y0, th))
    return out


def _start_x(array: PillarArray) -> float:
    """x of the starts: the middle of the gap between row −1 and row 0 [µm]."""
    x0, _, x1, _ = array.shape.bounds
    return 0.5 * (x0 + x1 - array.period_x)


_WORKER: dict = {}


def _init_worker(cfg_json: str, fields: dict) -> None:
    _WORKER["cfg"] = ArrayConfig.model_validate_json(cfg_json)
    _WORKER["fields"] = fields


def prepare_run(cfg: ArrayConfig, field, length: float, x_end: float | None = None):
    """The kernel of one length in one cell field (:func:`fibersweep.fiber.rows.array_kernel`).

    ``x_end`` [µm]: where the run passes (default: ``sweep.rows`` rows after the start).
    """
    from fibersweep.fiber.rows import array_kernel

    if x_end is None:
        x_end = _start_x(field.array) + cfg.sweep.rows * field.array.period_x
    return array_kernel(
        field,
        cfg.fiber,
        _n_beads(length, cfg.fiber.bead_radius),
        mu=cfg.flow.viscosity,
        u_center=cfg.flow.u_center,
        x_end=x_end,
    )


def run_one(cfg: ArrayConfig, field, length: float, y0: float, theta0: float) -> dict:
    """One run: its summary and thinned trajectory (a row of the store, without indices)."""
    from fibersweep.analysis.modes import ModeSettings, summarise_rows
    from fibersweep.fiber import record as R
    from fibersweep.fiber.rows import run_array_fiber

    k = prepare_run(cfg, field, length)
    x0 = _start_x(field.array)
    rec, code = run_array_fiber(k, cfg.fiber.model, x0, y0, math.radians(theta0))
    status = {R.PASSED: "done", R.TRAPPED: "trapped", R.TIME_LIMIT: "timeout"}.get(code, "failed")
    t = rec[:, R.T]
    npil = rec[:, R.CONTACT]  # pillars in contact
    contact = (npil > 0.5).astype(np.float64)
    rising = int(np.sum(np.diff(np.concatenate([[0.0], contact])) > 0.5))
    on = float(np.sum(np.diff(t) * contact[:-1])) if t.size > 1 else 0.0
    keep = cfg.sweep.samples_per_row * cfg.sweep.rows
    idx = np.unique(np.concatenate([
        np.linspace(0, rec.shape[0] - 1, min(keep, rec.shape[0])).astype(int),
        np.flatnonzero(np.diff(contact) != 0), np.flatnonzero(np.diff(contact) != 0) + 1,
    ]))  # fmt: skip
    cols = {"t": R.T, "xc": R.XC, "yc": R.YC, "th": R.TH, "speed": R.COM_SPEED}
    traj = {c: rec[idx, j] for c, j in cols.items()}
    traj["contact"] = contact[idx]
    arr = field.array
    summ = summarise_rows(traj, arr.period_x, arr.lateral_shift,
                          ModeSettings(trap_speed=k.params.trap_speed))  # fmt: skip
    return {
        "length": length, "n_beads": int(k.body.s.shape[0]), "y0": y0, "theta0": theta0,
        "status": status, "rows": summ.rows, "shift_per_row": summ.shift_per_row,
        "migration_angle": summ.angle_deg, "fraction": summ.fraction, "mode": summ.mode,
        "wraps": summ.wraps, "contacts": rising, "bridging": int(np.sum(npil >= 2)),
        "time_on_pillars": on, "t_end": float(t[-1]),
        **{f"traj_{c}": traj[c].tolist() for c in ("t", "xc", "yc", "th", "contact", "speed")},
    }  # fmt: skip


def _task(task: tuple) -> dict:
    setting, label, li, start, length, y0, th = task
    row = run_one(_WORKER["cfg"], _WORKER["fields"][setting], length, y0, th)
    return {"setting": setting, "setting_label": label, "start": start, **row}


def _execute(cfg: ArrayConfig, fields: dict, tasks: list, workers: int, progress) -> list:
    """Run ``tasks`` on ``workers`` processes (1: in this process); rows in task order."""
    rows = []
    if workers <= 1:
        _init_worker(cfg.model_dump_json(), fields)
        for i, t in enumerate(tasks):
            rows.append(_task(t))
            if progress:
                progress(i + 1, len(tasks))
        return rows
    with ProcessPoolExecutor(workers, initializer=_init_worker,
                             initargs=(cfg.model_dump_json(), fields)) as ex:  # fmt: skip
        chunk = max(1, len(tasks) // (8 * workers))
        for i, r in enumerate(ex.map(_task, tasks, chunksize=chunk)):
            rows.append(r)
            if progress:
                progress(i + 1, len(tasks))
    return rows


def _length_tasks(cfg, si, label, li, length, array, pillar) -> list[tuple]:
    n = _n_beads(length, cfg.fiber.bead_radius)
    starts = draw_starts(cfg, si, li, array, pillar, n)
    return [(si, label, li, k, float(length), y0, th) for k, (y0, th) in enumerate(starts)]


def refine_lengths(runs, level: float = 0.5) -> dict[int, list[float]]:
    """Per setting, the midpoints of neighbouring lengths whose mean fraction brackets ``level``.

    The next round of an adaptive search for the critical length (a pure
    function of the runs; trapped runs are left out of the means).
    """
    out: dict[int, list[float]] = {}
    moving = runs[runs["mode"] != "trapped"]
    for s, g in moving.groupby("setting"):
        f = g.groupby("length")["fraction"].mean().sort_index()
        L = f.index.to_numpy()
        d = f.to_numpy() - level
        out[int(s)] = [
            0.5 * (L[k] + L[k + 1]) for k in range(len(L) - 1) if np.isfinite(d[k] * d[k + 1])
            and d[k] * d[k + 1] < 0
        ]  # fmt: skip
    return out


def run_array_sweep(cfg: ArrayConfig, workers: int | None = None, progress=None,
                    refine: int = 0):  # fmt: skip
    """Run every (setting, length, start) and write ``run.output``/runs.parquet.

    ``refine``: rounds of bisection of the critical length; each round adds,
    for every setting, the midpoint of each pair of neighbouring lengths whose
    mean displacement fraction brackets 1/2 (:func:`refine_lengths`), with
    ``sweep.starts`` new seeded starts (seeded by the round, so reproducible).

    Returns the runs as a pandas DataFrame.
    """
    import pandas as pd

    from fibersweep.fiber.contact import make_pillar

    grid = settings_grid(cfg)
    fields, tasks, pillars = {}, [], {}
    for si, (label, s) in enumerate(grid):
        fields[si] = cell_field(s, cfg.flow, cfg.run.cache_dir)
        log.info("setting %d (%s): field ready, mean-flow angle %.2f deg", si, label or "base",
                 fields[si].meta["mean_flow_angle_deg"])  # fmt: skip
        array = fields[si].array
        pillars[si] = make_pillar(array.cell_geometry, cfg.fiber.contact,
                                  cfg.fiber.bead_radius, 1.0)  # fmt: skip
        for li, L in enumerate(cfg.sweep.length):
            tasks += _length_tasks(cfg, si, label, li, L, array, pillars[si])
    workers = workers or cfg.run.workers
    rows = _execute(cfg, fields, tasks, workers, progress)
    for rnd in range(refine):
        new = refine_lengths(pd.DataFrame(rows))
        tasks = []
        for si, lengths in new.items():
            for j, L in enumerate(lengths):
                li = 1000 * (rnd + 1) + j  # seeds apart from the base lengths
                tasks += _length_tasks(cfg, si, grid[si][0], li, L, fields[si].array,
                                       pillars[si])  # fmt: skip
        if not tasks:
            break
        log.info("refinement round %d: %d runs at %s", rnd + 1, len(tasks), new)
        rows += _execute(cfg, fields, tasks, workers, progress)
    df = pd.DataFrame(rows)
    out = Path(cfg.run.output)
    out.mkdir(parents=True, exist_ok=True)
    df.to_parquet(out / "runs.parquet")
    meta = {
        "config": json.loads(cfg.model_dump_json()),
        "settings": [
            {"label": lab, "array": s, **fields[i].array.describe(), "field": fields[i].meta}
            for i, (lab, s) in enumerate(grid)
        ],
    }
    (out / "array.json").write_text(json.dumps(meta, indent=1, default=str))
    for i in fields:
        save_field(fields[i], out / f"field-{i}.npz")
    return df
