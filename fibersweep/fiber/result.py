"""What one fiber run returns: a frozen record plus an optional trajectory.

This is the contract between the fiber dynamics (which fills it), the sweep
(which stores ``RunResult.row()`` in Parquet and the trajectory in a second
dataset) and the analysis (which re-classifies from the trajectory).

It is also the one schema of the per-run columns: every field of
:class:`FiberStart` and :class:`RunResult` carries its unit, description and
Arrow type as dataclass field metadata (:func:`column`), and the results
table's column types and docs (:data:`fibersweep.sweep.store.RUN_COLUMNS`,
:data:`~fibersweep.sweep.store.COLUMN_DOCS`) are generated from them
(:func:`record_columns`). A new per-run quantity is a field here and the line
of the case that measures it (``fiber/channel.py``, ``fiber/array_run.py``).
"""

from __future__ import annotations

import math
from dataclasses import MISSING, dataclass, field, fields
from typing import Any, Literal, NamedTuple

from fibersweep.analysis.trajectory import CLASSES, Trajectory

__all__ = [
    "ARRAY_COLUMNS",
    "CLASSES",
    "STATUSES",
    "Column",
    "FiberStart",
    "RunResult",
    "Trajectory",
    "column",
    "record_columns",
]

STATUSES = ("ok", "failed")

#: Arrow type names a column may declare (``pyarrow.type_for_alias`` names).
ARROW_TYPES = ("float64", "int64", "bool", "string")

#: Columns of pillar-array runs only (``flow.array``): written to a table part only
#: when one of its runs has a ``mode``, so a channel's table is as before they existed.
ARRAY_COLUMNS = (
    "rows",
    "shift_per_row",
    "migration_angle",
    "fraction",
    "mode",
    "wraps",
    "contacts",
    "bridging",
    "time_on_pillars",
)

#: Field names of the record whose column is named otherwise in the table.
COLUMN_NAMES = {"cls": "class"}


class Column(NamedTuple):
    """One per-run column of the results table.

    Attributes
    ----------
    name : str
        Column name.
    arrow : str
        Arrow type name ('float64', 'int64', 'bool' or 'string').
    unit : str
        Unit ('' for none), e.g. 'µm', 's', 'deg', 'h_obs'.
    doc : str
        What the column holds, in its frame.
    """

    name: str
    arrow: str
    unit: str
    doc: str


def column(default: Any, arrow: str, unit: str, doc: str, **kw: Any) -> Any:
    """A dataclass field that is a results-table column (its unit, doc and Arrow type).

    Parameters
    ----------
    default : Any
        Default value (``dataclasses.MISSING`` for a required field).
    arrow : str
        Arrow type name, one of :data:`ARROW_TYPES`.
    unit, doc : str
        Unit and description stored with the column (Parquet field metadata).
    **kw
        Further ``dataclasses.field`` arguments.
    """
    if arrow not in ARROW_TYPES:
        raise ValueError(f"arrow type {arrow!r}; valid: {', '.join(ARROW_TYPES)}")
    return field(default=default, metadata={"arrow": arrow, "unit": unit, "doc": doc}, **kw)


@dataclass(frozen=True)
class FiberStart:
    """Initial condition of a run, in the model's normalised units.

    Attributes
    ----------
    theta0 : float
        Angle from +x, counter-clockwise [degrees].
    y0 : float
        Centre-of-mass lateral position from the pillar base / h_obs (a pillar
        array: fraction of period_y in the gap upstream of row 0, 0..1).
    length : float
        Fiber length L / l_obs (a pillar array: L in µm).
    """

    theta0: float = column(
        MISSING, "float64", "deg", "start angle of the tail-to-head vector from +x (flow direction)"
    )
    y0: float = column(
        MISSING,
        "float64",
        "h_obs",
        "start lateral position of the centre of mass, from the pillar base line",
    )
    length: float = column(MISSING, "float64", "l_obs", "fiber length over the pillar base length")


@dataclass(frozen=True)
class RunResult:
    """Outcome of one fiber run.

    Attributes
    ----------
    start : FiberStart
    status : {'ok', 'failed'}
    reason : str
        Why a run failed ('' when ok), e.g. 'nan', 'penetration', 'time limit'.
    cls : str
        One of CLASSES, or '' when failed.
    delta : float
        (y_f - y0) / h_obs far downstream; NaN for Trapping or failure.
    contact : bool
        Whether the contact force ever became non-zero.
    theta_c, y_c : float
        Fiber angle [deg] and contact point lateral position / h_obs at first
        contact (NaN without contact).
    t_contact, t_pass : float
        Time of first contact and time to pass the pillar [s] (NaN if none).
    x_f, y_f, theta_f : float
        Final centre of mass [µm] and angle [deg].
    n_steps : int
    wall_time : float
        Seconds of computation.
    model : str
        Fiber model (rigid or bead-spring).
    integrator : str
        Its time integrator (midpoint; bdf2, ros2 or ros34pw2).
    n_beads : int
        Beads of the fiber (0 when the run did not start).
    t_end : float
        Time at the end of the run [s].
    min_clearance : float
        Smallest bead-centre distance to the pillar outline minus a, over the run [µm].
    max_curvature : float
        Largest curvature of the fiber over the run [1/µm] (bead-spring models;
        NaN for rigid; :mod:`fibersweep.fiber.models.deformation`).
    min_end_to_end : float
        Smallest end-to-end distance over contour length over the run (NaN for rigid).
    max_tension : float
        Largest stretching-spring tension over the run [pN] (NaN for rigid).
    max_wrap : float
        Largest angle the fiber's tangent turns along its beads on the pillar [deg]
        (NaN for rigid).
    trajectory : Trajectory or None
    """

    start: FiberStart
    status: Literal["ok", "failed"] = column(MISSING, "string", "", "ok or failed")
    reason: str = column("", "string", "", "why a run failed")
    cls: str = column(
        "", "string", "", "Below, Above, Pole-vaulting or Trapping (empty when failed)"
    )
    delta: float = column(
        math.nan,
        "float64",
        "h_obs",
        "lateral displacement y_f - y0 far downstream (NaN for Trapping)",
    )
    contact: bool = column(False, "bool", "", "whether the fiber touched the pillar")
    theta_c: float = column(
        math.nan, "float64", "deg", "fiber angle at first contact, in (-90, 90]"
    )
    y_c: float = column(
        math.nan,
        "float64",
        "h_obs",
        "lateral position of the first contact point, from the base line",
    )
    t_contact: float = column(math.nan, "float64", "s", "time of first contact")
    t_pass: float = column(
        math.nan, "float64", "s", "time the centre of mass passes the pillar's downstream end"
    )
    x_f: float = column(
        math.nan, "float64", "µm", "final centre-of-mass x, channel frame (inlet at 0)"
    )
    y_f: float = column(
        math.nan, "float64", "µm", "final centre-of-mass y, channel frame (wall at 0)"
    )
    theta_f: float = column(math.nan, "float64", "deg", "final directed angle, unwrapped")
    n_steps: int = column(0, "int64", "", "integrator steps")
    wall_time: float = column(0.0, "float64", "s", "wall-clock time of the run")
    model: str = column("", "string", "", "fiber model (rigid or bead-spring)")
    integrator: str = column(
        "", "string", "", "time integrator of the model (rigid: midpoint; bead-spring: bdf2, "
        "ros2 or ros34pw2)"
    )
    n_beads: int = column(0, "int64", "", "beads of the fiber (0 when the run did not start)")
    t_end: float = column(
        math.nan, "float64", "s", "time at the end of the run (stop or time limit)"
    )
    min_clearance: float = column(
        math.nan,
        "float64",
        "µm",
        "smallest bead-centre distance to the pillar outline minus the bead radius, over the run",
    )
    max_curvature: float = column(
        math.nan, "float64", "1/µm", "largest fiber curvature over the run (NaN for rigid)"
    )
    min_end_to_end: float = column(
        math.nan,
        "float64",
        "",
        "smallest end-to-end distance / contour length over the run (NaN for rigid)",
    )
    max_tension: float = column(
        math.nan,
        "float64",
        "pN",
        "largest stretching-spring tension over the run (NaN for rigid)",
    )
    max_wrap: float = column(
        math.nan,
        "float64",
        "deg",
        "largest turning of the tangent along the beads on the pillar (NaN for rigid)",
    )
    rows: int | None = column(
        None, "int64", "", "pillar arrays: whole rows of pillars crossed (null in a channel)"
    )
    shift_per_row: float = column(
        math.nan, "float64", "µm", "pillar arrays: mean lateral displacement per row"
    )
    migration_angle: float = column(
        math.nan, "float64", "deg", "pillar arrays: atan(shift_per_row / period_x)"
    )
    fraction: float = column(
        math.nan,
        "float64",
        "",
        "pillar arrays: shift_per_row / (shift period_y); 1 follows the tilt, 0 the flow",
    )
    mode: str | None = column(
        None,
        "string",
        "",
        "pillar arrays: zigzag, displacement, wrap-and-jump, trapped or mixed (null in a channel)",
    )
    wraps: int | None = column(
        None, "int64", "", "pillar arrays: contact episodes with a turn beyond 90 deg"
    )
    contacts: int | None = column(
        None, "int64", "", "pillar arrays: contact episodes (from every step)"
    )
    bridging: int | None = column(
        None, "int64", "", "pillar arrays: steps in contact with two or more pillars at once"
    )
    time_on_pillars: float = column(
        math.nan, "float64", "s", "pillar arrays: time in contact with a pillar"
    )
    trajectory: Trajectory | None = field(default=None, compare=False, repr=False)

    def row(self) -> dict[str, object]:
        """Flat scalar columns for the results table (one row per run)."""
        # Not asdict(): it would deep-copy the trajectory only to drop it.
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d.pop("trajectory")
        start = d.pop("start")
        return {
            "theta0": start.theta0,
            "y0": start.y0,
            "length": start.length,
            "class": d.pop("cls"),
            **d,
        }


def record_columns() -> tuple[Column, ...]:
    """The per-run columns of the record, in table order: the start, then each result field.

    The trajectory (a dataset of its own) is not a column; ``cls`` is named ``class``.

    Returns
    -------
    tuple of Column
    """
    out = [Column(f.name, **f.metadata) for f in fields(FiberStart)]
    for f in fields(RunResult):
        if "arrow" in f.metadata:
            out.append(Column(COLUMN_NAMES.get(f.name, f.name), **f.metadata))
    return tuple(out)
