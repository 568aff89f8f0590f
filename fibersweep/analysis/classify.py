"""Classification of a fiber run as a pure function of its recorded trajectory.

Rules (docs/model.md; thresholds in :class:`ClassifySettings`):

1. **Trapping**: the fiber is in contact and its centre of mass moves slower
   than ``trap_speed``·|U_center| for at least ``trap_time`` (consecutive
   samples, duration = last − first sample time of the run of such samples).
2. **Pole-vaulting**: head and tail swap (the directed tail→head angle turns by
   more than 90° between the first and last sample) and the turn is a vault by
   the chosen rule (:data:`RULES`, ``ClassifySettings.rule``):

   * ``head-speed`` (the source's rule): while in contact the head
     (the bead that leads at the start) is blocked, speed below
     ``head_blocked_speed``·|U_center|, at some sample;
   * ``pivot``: from the first contact until the fiber has turned through 90°,
     the head travels less than ``pivot_fraction``·L: the fiber turns about its
     head instead of sliding past;
   * ``switch`` (default: it agrees best with runs labelled by eye,
     docs/fidelity.md): the fiber touched the pillar (front and rear switch
     after a contact, whatever the head did);
   * ``corner``: the head stays within ``corner_fraction``·L of one pillar
     corner while the fiber turns through ``corner_turn`` degrees, with a
     contact on the way: the fiber swings about its head held at the corner
     (a circle has no corner: there the head is held near one point of the
     outline).
3. Otherwise **Above** / **Below**: the side of the pillar centroid on which
   the centre of mass is when it crosses the centroid's x (first crossing in
   the flow direction).

A trajectory that neither crossed nor got trapped gives '' (undetermined).
The integrators call the same function on their full-resolution record; a
stored (thinned) trajectory keeps the samples these rules need, so
re-classifying with other thresholds needs no new simulation.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from fibersweep.analysis.trajectory import Trajectory
from fibersweep.geometry import ConvexPolygon
from fibersweep.units import Geometry

__all__ = [
    "RULES",
    "ClassifySettings",
    "Rule",
    "classify",
    "classify_all",
    "held_turn",
    "longest_run",
    "pass_crossing",
    "pivot_points",
    "stopped_mask",
]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class ClassifySettings(_Strict):
    """Thresholds of the classification and its pole-vaulting rule.

    They live with the rules they parameterise: ``rule`` must name an entry of
    :data:`RULES`, the registry that decides which rules exist.
    """

    head_blocked_speed: float = Field(
        0.01, gt=0, description="head counts as blocked below this fraction of U_center"
    )
    trap_time: float = Field(
        2.0, gt=0, description="in contact and stopped for this long [s] -> Trapping"
    )
    trap_speed: float = Field(
        0.01, gt=0, description="'stopped' means COM speed below this fraction of U_center"
    )
    rule: str = Field(
        "switch",
        description=(
            "pole-vaulting rule: switch (default: agrees best with a person's eye, "
            "docs/fidelity.md), head-speed (the source's), pivot or corner"
        ),
    )
    pivot_fraction: float = Field(
        0.5, gt=0, description="pivot rule: the head moves less than this x L while turning 90°"
    )
    corner_fraction: float = Field(
        0.3,
        gt=0,
        le=1,
        description="corner rule: the head stays within this x L of a pillar corner ...",
    )
    corner_turn: float = Field(
        90.0, gt=0, le=180, description="corner rule: ... while the fiber turns this much [deg]"
    )

    @field_validator("rule")
    @classmethod
    def _known_rule(cls, name: str) -> str:
        if name not in RULES:
            raise ValueError(f"unknown rule; valid: {', '.join(RULES)}")
        return name


def stopped_mask(traj: Trajectory, u_center: float, thresholds: ClassifySettings) -> np.ndarray:
    """Samples in contact and slower than the trap speed, shape (m,) bool."""
    contact = np.asarray(traj.contact, dtype=bool)
    return contact & (np.asarray(traj.com_speed) < thresholds.trap_speed * abs(u_center))


def longest_run(t: np.ndarray, mask: np.ndarray) -> float:
    """Longest duration [s] (last − first time) of consecutive True samples; 0 if none."""
    if not np.any(mask):
        return 0.0
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    starts = np.flatnonzero(~m[:-1] & m[1:])
    ends = np.flatnonzero(m[:-1] & ~m[1:]) - 1
    return float(np.max(np.asarray(t)[ends] - np.asarray(t)[starts]))


def pass_crossing(traj: Trajectory, geometry: Geometry, u_center: float) -> float:
    """y [µm] of the centre of mass where it first crosses the pillar centroid's x; NaN if never."""
    xp = geometry.centroid[0]
    sign = 1.0 if u_center >= 0 else -1.0
    x = sign * (np.asarray(traj.x) - xp)
    idx = np.flatnonzero((x[:-1] < 0.0) & (x[1:] >= 0.0))
    if idx.size == 0:
        return float("nan")
    k = int(idx[0])
    w = -x[k] / (x[k + 1] - x[k])
    return float(traj.y[k] + w * (traj.y[k + 1] - traj.y[k]))


def _head_blocked(tr: Trajectory, u_center: float, th: ClassifySettings) -> bool:
    contact = np.asarray(tr.contact, dtype=bool)
    slow = np.asarray(tr.head_speed) < th.head_blocked_speed * abs(u_center)
    return bool(np.any(contact & slow))


def _pivots(tr: Trajectory, u_center: float, th: ClassifySettings) -> bool:
    contact = np.flatnonzero(np.asarray(tr.contact, dtype=bool))
    if contact.size == 0:
        return False
    k0 = int(contact[0])
    theta = np.asarray(tr.theta, dtype=np.float64)
    turned = np.flatnonzero(np.abs(theta[k0:] - theta[k0]) >= 90.0)
    if turned.size == 0:
        return False
    k1 = k0 + int(turned[0])
    head = np.asarray(tr.head, dtype=np.float64)
    length = float(np.hypot(*(head[0] - np.asarray(tr.tail[0], dtype=np.float64))))
    travel = float(np.sum(np.hypot(*np.diff(head[k0 : k1 + 1], axis=0).T)))
    return travel < th.pivot_fraction * length


def _touched(tr: Trajectory, u_center: float, th: ClassifySettings) -> bool:
    return bool(np.any(np.asarray(tr.contact, dtype=bool)))


def pivot_points(geometry: Geometry, head: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Points of the pillar a head can be held at, shape (k, 2) [µm].

    The corners of a polygon pillar; a circle has none, so there every point of
    its outline nearest to the head at a sample in contact is a candidate.

    Parameters
    ----------
    geometry : Geometry
    head : ndarray, shape (m, 2)
        Head positions [µm].
    contact : ndarray, shape (m,), bool
    """
    shape = geometry.shape
    if isinstance(shape, ConvexPolygon):
        return np.asarray(shape.vertices, dtype=np.float64)
    near, _, _ = shape.nearest(head[contact, 0], head[contact, 1])
    return near.reshape(-1, 2)


def held_turn(
    head: np.ndarray, theta: np.ndarray, contact: np.ndarray, point: np.ndarray, radius: float
) -> float:
    """Largest turn [deg] of the fiber while its head stays within ``radius`` of ``point``.

    Over each stretch of consecutive samples with the head within ``radius`` [µm]
    of ``point`` that includes a contact, the turn is the range (max − min) of the
    unwrapped angle; the largest over the stretches, 0 if there is none.

    Parameters
    ----------
    head : ndarray, shape (m, 2)
        Head positions [µm].
    theta : ndarray, shape (m,)
        Unwrapped tail-to-head angle [deg].
    contact : ndarray, shape (m,), bool
    point : ndarray, shape (2,)
        The pivot [µm].
    radius : float
        [µm].
    """
    near = np.hypot(head[:, 0] - point[0], head[:, 1] - point[1]) <= radius
    if not np.any(near & contact):
        return 0.0
    m = np.concatenate([[False], near, [False]])
    starts = np.flatnonzero(~m[:-1] & m[1:])
    ends = np.flatnonzero(m[:-1] & ~m[1:])
    best = 0.0
    for a, b in zip(starts, ends, strict=True):
        if np.any(contact[a:b]):
            best = max(best, float(np.max(theta[a:b]) - np.min(theta[a:b])))
    return best


def _corner_vault(
    tr: Trajectory, u_center: float, th: ClassifySettings, geometry: Geometry
) -> bool:
    head = np.asarray(tr.head, dtype=np.float64)
    contact = np.asarray(tr.contact, dtype=bool)
    if not np.any(contact):
        return False
    theta = np.asarray(tr.theta, dtype=np.float64)
    length = float(np.hypot(*(head[0] - np.asarray(tr.tail[0], dtype=np.float64))))
    radius = th.corner_fraction * length
    return any(
        held_turn(head, theta, contact, p, radius) >= th.corner_turn
        for p in pivot_points(geometry, head, contact)
    )


@dataclass(frozen=True)
class Rule:
    """A pole-vaulting rule: given that head and tail swapped, was it a vault?

    Attributes
    ----------
    name : str
    description : str
    vaulted : callable
        ``(trajectory, u_center [µm/s], thresholds) -> bool``; a pure function of
        the stored trajectory. With ``needs_geometry`` it takes the pillar's
        :class:`Geometry` as a fourth argument.
    needs_geometry : bool
        The rule looks at where the pillar is (its corners).
    """

    name: str
    description: str
    vaulted: Callable[..., bool]
    needs_geometry: bool = False

    def applies(
        self, trajectory: Trajectory, geometry: Geometry, u_center: float, th: ClassifySettings
    ) -> bool:
        """Whether the rule calls this swap a vault (``vaulted`` with what it needs)."""
        if self.needs_geometry:
            return bool(self.vaulted(trajectory, u_center, th, geometry))
        return bool(self.vaulted(trajectory, u_center, th))


#: Pole-vaulting rules by name; ``switch`` is the default, ``head-speed`` the source's.
RULES: dict[str, Rule] = {
    r.name: r
    for r in (
        Rule("head-speed", "head blocked (speed < head_blocked_speed U) in contact", _head_blocked),
        Rule("pivot", "head travels < pivot_fraction L while turning 90° after contact", _pivots),
        Rule("switch", "front and rear switch after a contact", _touched),
        Rule(
            "corner",
            "head held within corner_fraction L of a pillar corner while the fiber turns "
            "corner_turn degrees",
            _corner_vault,
            needs_geometry=True,
        ),
    )
}


def classify(
    trajectory: Trajectory,
    geometry: Geometry,
    u_center: float,
    thresholds: ClassifySettings,
    rule: str | None = None,
) -> str:
    """Class of a run: 'Below', 'Above', 'Pole-vaulting', 'Trapping', or '' if undetermined.

    Parameters
    ----------
    trajectory : Trajectory
        Time-ordered samples (full resolution or thinned).
    geometry : Geometry
        Channel and pillar.
    u_center : float
        Centreline speed of the field the run used [µm/s] (its sign is the flow direction).
    thresholds : ClassifySettings
    rule : str, optional
        Pole-vaulting rule from :data:`RULES`; default ``thresholds.rule``.

    Raises
    ------
    KeyError
        Unknown rule (the config and the CLI check names against :data:`RULES`).
    """
    chosen = RULES[rule or thresholds.rule]
    tr = trajectory
    if len(tr.t) < 2:
        return ""
    if longest_run(tr.t, stopped_mask(tr, u_center, thresholds)) >= thresholds.trap_time:
        return "Trapping"
    swapped = abs(float(tr.theta[-1]) - float(tr.theta[0])) > 90.0
    y_cross = pass_crossing(tr, geometry, u_center)
    if np.isnan(y_cross):
        return ""
    if swapped and chosen.applies(tr, geometry, u_center, thresholds):
        return "Pole-vaulting"
    return "Above" if y_cross > geometry.centroid[1] else "Below"


def classify_all(
    trajectory: Trajectory, geometry: Geometry, u_center: float, thresholds: ClassifySettings
) -> dict[str, str]:
    """The class of a run under every rule of :data:`RULES` (name -> class)."""
    return {name: classify(trajectory, geometry, u_center, thresholds, name) for name in RULES}
