"""Classification rules on synthetic trajectories, and thinning."""

from __future__ import annotations

import numpy as np
import pytest

from fibersweep.analysis.classify import classify, longest_run
from fibersweep.analysis.observables import fiber_angle, take, thin_indices
from fibersweep.config.fiber import ClassifySettings
from fibersweep.fiber.result import Trajectory
from fibersweep.units import Geometry

GEO = Geometry()
U = 600.0
TH = ClassifySettings()
XC, YC = GEO.centroid


def _traj(t, x, y, theta, head_speed, com_speed, contact) -> Trajectory:
    m = len(t)
    z = np.zeros((m, 2))
    return Trajectory(
        t=np.asarray(t, float), x=np.asarray(x, float), y=np.asarray(y, float),
        theta=np.asarray(theta, float), head=z, tail=z,
        head_speed=np.asarray(head_speed, float), com_speed=np.asarray(com_speed, float),
        contact=np.asarray(contact, bool),
    )  # fmt: skip


def _passing(dy, theta_end=0.0, head_min=100.0, contact=False, m=401):
    t = np.linspace(0, 2, m)
    x = XC - 300 + 600 * t / 2
    y = np.full(m, YC + dy)
    theta = np.linspace(0, theta_end, m)
    hs = np.full(m, 300.0)
    c = np.zeros(m, bool)
    if contact:
        c[150:250] = True
        hs[200] = head_min
    return _traj(t, x, y, theta, hs, np.full(m, 300.0), c)


def test_above_below_by_side_of_centroid():
    assert classify(_passing(+40), GEO, U, TH) == "Above"
    assert classify(_passing(-40), GEO, U, TH) == "Below"
    # reversed flow: crossing in −x
    tr = _passing(+40)
    rev = _traj(tr.t, tr.x[::-1], tr.y, tr.theta, tr.head_speed, tr.com_speed, tr.contact)
    assert classify(rev, GEO, -U, TH) == "Above"


def test_head_speed_vault_needs_blocked_head_and_swap():
    hs = ClassifySettings(rule="head-speed")  # the source's rule
    assert classify(_passing(40, 180, head_min=1.0, contact=True), GEO, U, hs) == "Pole-vaulting"
    # head not blocked (above 0.01 U = 6 µm/s): the side decides
    assert classify(_passing(40, 180, head_min=50.0, contact=True), GEO, U, hs) == "Above"
    # ... unless the threshold is raised: re-classification without simulating
    loose = ClassifySettings(rule="head-speed", head_blocked_speed=0.1)
    assert classify(_passing(40, 180, head_min=50.0, contact=True), GEO, U, loose) == (
        "Pole-vaulting"
    )
    # blocked but no swap
    assert classify(_passing(-40, 30, head_min=1.0, contact=True), GEO, U, hs) == "Below"


def test_default_rule_is_switch_a_swap_after_contact():
    """The default (docs/fidelity.md: best agreement with the eye) needs a swap and a contact."""
    assert TH.rule == "switch"
    assert classify(_passing(40, 180, head_min=50.0, contact=True), GEO, U, TH) == "Pole-vaulting"
    assert classify(_passing(40, 180, head_min=50.0, contact=False), GEO, U, TH) == "Above"
    assert classify(_passing(-40, 30, head_min=1.0, contact=True), GEO, U, TH) == "Below"


def test_trapping_needs_contact_and_stop_for_trap_time():
    t = np.linspace(0, 5, 501)
    x = np.full(501, XC - 50)
    y = np.full(501, YC)
    slow = np.full(501, 1.0)
    contact = t > 1.0
    tr = _traj(t, x, y, np.zeros(501), slow, slow, contact)
    assert classify(tr, GEO, U, TH) == "Trapping"  # 4 s stopped in contact >= 2 s
    assert classify(tr, GEO, U, ClassifySettings(trap_time=4.5)) == ""  # never crossed
    tr2 = _traj(t, x, y, np.zeros(501), slow, slow, t > 3.5)
    assert classify(tr2, GEO, U, TH) == ""


def test_longest_run():
    t = np.arange(10.0)
    m = np.array([0, 1, 1, 0, 1, 1, 1, 1, 0, 1], bool)
    assert longest_run(t, m) == 3.0
    assert longest_run(t, np.zeros(10, bool)) == 0.0


def test_thinning_keeps_what_classification_needs():
    tr = _passing(40, 180, head_min=1.0, contact=True, m=20001)
    idx = thin_indices(tr, 200, U, TH)
    assert idx[0] == 0 and idx[-1] == len(tr.t) - 1
    assert len(idx) <= 200 + 2
    thin = take(tr, idx)
    assert thin.head_speed.min() == 1.0  # the blocked-head sample survives
    assert classify(thin, GEO, U, TH) == classify(tr, GEO, U, TH) == "Pole-vaulting"


@pytest.mark.parametrize(
    "theta, expect", [(0.0, 0.0), (170.0, -10.0), (-100.0, 80.0), (90.0, 90.0), (-90.0, 90.0)]
)
def test_fiber_angle(theta, expect):
    assert fiber_angle(theta) == pytest.approx(expect)


def _turning(head_path: str, m: int = 401, length: float = 100.0):
    """A fiber in contact that turns its tail->head angle from 0 to 180 degrees.

    head_path 'pivot': the head stays at one point (speed 0) and the tail swings round it;
    'slide': the fiber spins about its centre while drifting 3 L downstream, so the head
    travels several L while it turns (a flip while passing, not a vault).
    """
    t = np.linspace(0, 2, m)
    th = np.radians(np.linspace(0, 180, m))
    if head_path == "pivot":
        head = np.column_stack([np.full(m, XC - 20.0), np.full(m, YC + 60.0)])
        com = head - 0.5 * length * np.column_stack([np.cos(th), np.sin(th)])
    else:
        com = np.column_stack([XC - 150 + 3 * length * t / 2, np.full(m, YC + 60.0)])
        head = com + 0.5 * length * np.column_stack([np.cos(th), np.sin(th)])
    tail = 2 * com - head
    speed = np.hypot(*np.gradient(head, t, axis=0).T)
    # cross the centroid's x at the end so the run is classifiable
    x = np.r_[com[:-1, 0], XC + 200.0]
    return Trajectory(
        t=t, x=x, y=com[:, 1], theta=np.degrees(th), head=head, tail=tail,
        head_speed=speed, com_speed=np.full(m, 300.0), contact=np.ones(m, bool),
    )  # fmt: skip


@pytest.mark.parametrize(
    ("rule", "pivot", "slide"),
    [
        ("head-speed", "Pole-vaulting", "Above"),  # the sliding head never stops
        ("pivot", "Pole-vaulting", "Above"),  # head travel 0 vs about 2.4 L while turning
        ("switch", "Pole-vaulting", "Pole-vaulting"),  # any swap after contact
        ("corner", "Pole-vaulting", "Above"),  # head 22 µm (< 0.3 L) from the apex vs sliding
    ],
)
def test_every_rule_on_a_pivot_and_on_a_sliding_flip(rule, pivot, slide):
    from fibersweep.analysis.classify import RULES

    assert rule in RULES
    assert classify(_turning("pivot"), GEO, U, TH, rule) == pivot
    assert classify(_turning("slide"), GEO, U, TH, rule) == slide


def test_every_rule_is_tested_and_unknown_rules_are_refused():
    from pydantic import ValidationError

    from fibersweep.analysis.classify import RULES

    assert set(RULES) == {"head-speed", "pivot", "switch", "corner"}  # extend the table above
    with pytest.raises(ValidationError, match="unknown rule; valid: head-speed, pivot, switch, co"):
        ClassifySettings(rule="wobble")
