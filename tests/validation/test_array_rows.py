"""Fibers through the array: the periodic frame, one row against the channel's integrator,
a fiber bridging two pillars."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fibersweep.analysis.modes import row_crossings
from fibersweep.config.fiber import FiberSettings
from fibersweep.config.flow import FlowSettings
from fibersweep.fiber.frame import frame_velocity
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.rows import run_array_fiber
from fibersweep.fiber.run import simulate
from fibersweep.flow.cell import field_of, first_streamline_width, solve_cell
from fibersweep.flow.field import FlowField
from fibersweep.units import Fluid


def prepare_run(fiber: FiberSettings, field, length: float, x_end: float | None = None):
    from fibersweep.fiber.array_run import array_run_kernel

    return array_run_kernel(field, fiber, length, x_end)


@pytest.fixture(scope="module")
def small():
    """Triangles 40 µm high, 80 µm periods, ε = 0.1, dx = 4 µm."""
    flow = FlowSettings.model_validate({"dx": 4.0, "array": {}})
    return FiberSettings(), field_of(flow, solve_cell(flow))


def test_velocity_is_the_same_at_every_periodic_image(small):
    """Bead positions moved by any lattice vector (r λx, r ε λy + c λy) see the same
    velocity (fold + padded cell field; tolerance: rounding, 1e-9 µm/s)."""
    cfg, field = small
    k = prepare_run(cfg, field, 20.0)
    rng = np.random.default_rng(1)
    x = rng.uniform(0, 80, 50)
    y = rng.uniform(0, 80, 50)
    ref = np.zeros((50, 2))
    frame = k.frame._replace(xs=np.zeros(50), ys=np.zeros(50))  # scratch for 50 points
    frame_velocity(frame, k.flow, x, y, ref)
    assert np.abs(ref).max() > 100.0
    for r, c in [(1, 0), (-3, 2), (7, -1), (25, 4)]:
        out = np.zeros((50, 2))
        frame_velocity(frame, k.flow, x + r * 80.0, y + r * 8.0 + c * 80.0, out)
        assert np.abs(out - ref).max() < 1e-9


def test_long_fiber_across_a_gap_bridges_two_pillars_and_is_trapped(small):
    """A rigid fiber longer than λy held across the flow hits two pillars at once."""
    cfg, field = small
    arr = field.array
    k = prepare_run(cfg, field, 120.0)
    x0 = arr.shape.bounds[0] - 10.0  # just upstream of the row-0 pillar
    rec, code = run_array_fiber(k, "rigid", x0, 40.0, math.pi / 2)
    assert code == R.TRAPPED
    assert rec[-1, R.CONTACT] >= 2  # in contact with two pillars when it stops


def test_friction_acts_in_the_array(small):
    """The array runs the channel's integrator with its effects: Coulomb friction on the
    pillars slows a 40 µm fiber sliding past them, so crossing 3 rows takes longer as the
    coefficient grows (0, 0.3, 1), for two entries that touch pillars and pass. (The
    integrator of the first array version had no effects: equal times.)"""
    cfg, field = small
    x0 = field.array.shape.bounds[0] - 0.5 * field.array.row_gap
    for y0 in (45.0, 60.0):
        ends = []
        for mu in (0.0, 0.3, 1.0):
            fiber = cfg.model_copy(update={"effects": {"friction": mu}})
            k = prepare_run(fiber, field, 40.0, x_end=x0 + 3 * field.array.period_x)
            rec, code = run_array_fiber(k, "rigid", x0, y0, 0.0)
            assert code == R.PASSED and rec[:, R.CONTACT].max() >= 1
            ends.append(rec[-1, R.T])
        assert ends[0] < ends[1] < ends[2], (y0, ends)


@pytest.mark.slow
def test_one_pillar_of_a_sparse_array_as_the_channel_integrator():
    """Period >> fiber: crossing one pillar with the array tracker and with the channel's
    rigid integrator, on the same cell field, from the same local start.

    Both use the same mobility, contact kernel, interpolation and step rule;
    they differ only in the frame (folded images vs one pillar). Measured:
    identical to the last bit while no implicit stopped step is taken.
    Tolerance: 1e-6 µm in y, 1e-6° in angle at the end.
    """
    flow = FlowSettings.model_validate({
        "array": {"pillar_size": 75.0, "period_x": 240.0, "period_y": 240.0, "shift": 0.0},
        "dx": 4.0,
    })  # fmt: skip
    arr = flow.array.to_array()
    cf = field_of(flow, solve_cell(flow))
    geo = arr.cell_geometry
    X, Y = np.meshgrid(*(np.arange(n) * 4.0 + 2.0 for n in cf.ux.shape), indexing="ij")
    ff = FlowField(cf.ux, cf.uy, 4.0, geo, Fluid(), geo.inside_pillar(X, Y))
    length = 0.5 * geo.pillar_base_length
    settings = FiberSettings.model_validate({
        "x0": 40.0, "record": {"trajectories": True, "samples": 2000},
        "step": {"x_end": 20.0},
    })  # fmt: skip
    for y0, th0 in [(0.3, -5.0), (0.45, 5.0), (0.38, 0.0)]:  # all touch the pillar
        res = simulate(ff, settings, FiberStart(th0, y0, length / geo.pillar_base_length))
        tr = res.trajectory
        k = prepare_run(FiberSettings(), cf, length, x_end=float(tr.x[-1]))
        rec, _ = run_array_fiber(k, "rigid", 40.0, geo.y_from_base(y0), math.radians(th0))
        y_end = np.interp(tr.x[-1], rec[:, R.XC], rec[:, R.YC])
        th_end = np.interp(tr.x[-1], rec[:, R.XC], rec[:, R.TH])
        assert res.trajectory.contact.any()  # each start touches the pillar
        assert y_end == pytest.approx(tr.y[-1], abs=1e-6)
        assert math.degrees(th_end) == pytest.approx(tr.theta[-1], abs=1e-6)


@pytest.mark.ci
@pytest.mark.slow
def test_one_bead_fiber_is_a_steric_sphere():
    """One bead (a sphere of diameter D = 2a) in circle posts, G = 40 µm, ε = 0.1, dx = 2 µm.

    A bead reads the flow at its centre and is displaced only by contact, so it
    must bump when its contact distance from the rough pillar's beads,
    1.1 (a + a_obs), exceeds the first-streamline width β of the simulated gap:
    D_c = 2 (β / 1.1 − a_obs). Check: spheres 20 % below D_c zigzag (|f| < 0.25),
    20 % above it are displaced (f > 0.75), 4 starts × 20 rows each; f over rows
    10 to 20, after the lock-in (a displaced sphere may first drift across up to
    1/ε = 10 lanes before it reaches the pillar's first streamline). (The
    empirical DLD law 1.4 G ε^0.48 = 18.5 µm is not met: docs/arrays.md.)
    """
    flow = FlowSettings.model_validate(
        {"array": {"pillar_shape": "circle", "shift": 0.1}, "dx": 2.0}
    )
    arr = flow.array.to_array()
    sol = solve_cell(flow)
    beta, _ = first_streamline_width(arr, sol.u, 2.0)
    field = field_of(flow, sol)
    d_c = 2.0 * (beta / 1.1 - 0.6)
    for scale, zigzag in ((0.8, True), (1.2, False)):
        a = 0.5 * scale * d_c
        c = FiberSettings(bead_radius=a)
        x0 = 0.5 * (arr.shape.bounds[0] + arr.shape.bounds[2] - arr.period_x)
        k = prepare_run(c, field, 2 * a, x_end=x0 + 20 * arr.period_x)
        for y0 in (5.0, 25.0, 55.0, 75.0):
            rec, _ = run_array_fiber(k, "rigid", x0, y0, 0.0)
            yc = row_crossings(rec[:, R.XC], rec[:, R.YC], arr.period_x)
            f = (yc[20] - yc[10]) / (10 * arr.lateral_shift)
            assert (abs(f) < 0.25) if zigzag else (f > 0.75), (scale, y0, f)


def test_simulate_on_a_cell_field_is_the_array_run(small):
    """``simulate`` dispatches on the field: on a unit cell it runs the array kernel
    from y0 = fraction of period_y in the gap upstream of row 0, for fiber.array_rows
    rows, and its record's array columns are the trajectory's summary. Checked
    against the kernel run directly from the same start: the same end (exact: the same
    arithmetic), and the summary of the stored (thinned) trajectory equal to the
    record's columns (exact: the same function)."""
    from fibersweep.analysis.modes import summarise_trajectory
    from fibersweep.fiber.array_run import start_x

    fiber, field = small
    fiber = fiber.model_copy(update={"array_rows": 4})
    arr = field.array
    res = simulate(field, fiber, FiberStart(theta0=3.0, y0=0.7, length=40.0))
    assert res.status == "ok" and res.cls == ""
    k = prepare_run(fiber, field, 40.0)
    rec, code = run_array_fiber(k, "rigid", start_x(arr), 0.7 * arr.period_y, math.radians(3.0))
    assert code == R.PASSED
    assert res.x_f == rec[-1, R.XC] and res.y_f == rec[-1, R.YC]
    assert res.rows >= 4 and res.n_beads == 10
    s = summarise_trajectory(res.trajectory, arr, k.params.trap_speed)
    assert (s.rows, s.mode, s.wraps) == (res.rows, res.mode, res.wraps)
    assert s.fraction == res.fraction and s.angle_deg == res.migration_angle
    assert res.contacts >= 0 and res.time_on_pillars >= 0.0


def test_simulate_for_on_a_cell_field_is_the_array_run_stopped_in_time(small):
    """``simulate_for`` takes the same path with the time stop rule: on a unit cell, the
    array's start and frame; its steps are those of the array run from the same start
    (exact: the same arithmetic) up to the last, which ends at the duration."""
    from fibersweep.fiber.array_run import start_x
    from fibersweep.fiber.run import simulate_for

    fiber, field = small
    arr = field.array
    traj, reason = simulate_for(field, fiber, FiberStart(theta0=3.0, y0=0.7, length=40.0), 0.05)
    assert reason == "" and traj.t[-1] == pytest.approx(0.05, abs=1e-12)
    k = prepare_run(fiber, field, 40.0)
    rec, code = run_array_fiber(k, "rigid", start_x(arr), 0.7 * arr.period_y, math.radians(3.0))
    m = traj.t.size - 1
    assert code == R.PASSED and rec[m, R.T] > 0.05
    assert np.array_equal(rec[:m, R.T], traj.t[:m]) and np.array_equal(rec[:m, R.XC], traj.x[:m])
    assert np.array_equal(rec[:m, R.YC], traj.y[:m])


def test_a_start_on_a_pillar_or_outside_the_cell_is_bad_input(small):
    """Bad starts raise InputError naming y0 (a sweep records them as failed runs)."""
    from fibersweep.errors import InputError
    from fibersweep.fiber.array_run import start_x

    fiber, field = small
    arr = field.array
    _, cy = arr.shape.centroid  # row 0's pillar, at the start's height
    with pytest.raises(InputError, match="^y0"):
        simulate(field, fiber, FiberStart(theta0=90.0, y0=1.5, length=20.0))
    # an 80 µm fiber along the flow, centred in the row gap, reaches into row 0's pillar
    assert start_x(arr) + 40.0 > arr.shape.bounds[0]
    with pytest.raises(InputError, match="touches a pillar"):
        simulate(field, fiber, FiberStart(theta0=0.0, y0=cy / arr.period_y, length=80.0))


@pytest.mark.parametrize("y0", [0.6, 0.9])
def test_stiff_bead_spring_fiber_follows_the_rigid_one_through_the_array(small, y0):
    """The flexible model runs in the array through the same frame: at E = 26 MPa a 60 µm
    fiber (15 beads) crosses 5 rows in the same mode as the rigid fiber, with its lateral
    shift per row within 0.5 µm of the rigid one (measured 0.16 and 0.02 µm; the channel
    holds rigid and bead-spring δ to 0.02 h_obs = 1.5 µm)."""
    cfg, field = small
    start = FiberStart(0.0, y0, 60.0)
    rigid = simulate(field, cfg.model_copy(update={"array_rows": 5}), start)
    stiff = cfg.model_copy(update={"model": "bead-spring", "integrator": "ros2", "array_rows": 5})
    flex = simulate(field, stiff, start)
    assert rigid.status == flex.status == "ok", (rigid, flex)
    assert flex.mode == rigid.mode and flex.rows == rigid.rows == 5
    assert abs(flex.shift_per_row - rigid.shift_per_row) < 0.5, (rigid, flex)
    assert math.isnan(rigid.max_curvature) and flex.max_curvature < 2e-3  # nearly straight


def test_softer_fibers_bend_more_around_the_array_pillars(small):
    """Deformation columns of array runs (wrap measured against the nearest pillar):
    the largest curvature and wrap angle grow as E falls 26 -> 1 -> 0.1 MPa (measured
    0.0009, 0.016, 0.14 1/µm and 0.2°, 3.6°, 25° for a 60 µm fiber at y0 = 0.6)."""
    cfg, field = small
    out = []
    for e in (26e6, 1e6, 1e5):
        fiber = cfg.model_copy(
            update={"model": "bead-spring", "integrator": "ros2", "young_modulus": e,
                    "array_rows": 5}  # fmt: skip
        )
        r = simulate(field, fiber, FiberStart(0.0, 0.6, 60.0))
        assert r.status == "ok" and r.contacts > 0, r
        out.append((r.max_curvature, r.max_wrap))
    curv, wrap = np.array(out).T
    assert np.all(np.diff(curv) > 0) and curv[-1] > 50 * curv[0], curv
    assert np.all(np.diff(wrap) > 0) and wrap[-1] > 10.0, wrap
