"""The single pillar in its channel: the channel case of the run path (:mod:`.case`).

- start placement: :func:`fibersweep.fiber.setup.prepare` (the effects' field and
  start, the checks of :func:`~fibersweep.fiber.setup.check_start`: θ0 [deg],
  y0 / h_obs, L / l_obs, x0 = a quarter of the channel unless ``fiber.x0``);
- stop rule and frame: :func:`fibersweep.fiber.kernel.bundles.build_kernel` (past
  ``step.x_end`` behind the pillar, between the side walls;
  :class:`~fibersweep.fiber.frame.Channel`);
- measurement: the class (:func:`fibersweep.analysis.classify.classify`), δ, the
  contact and pass quantities, the bead-spring deformation, the thinned
  trajectory, and the effects' report hooks last.
"""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np

from fibersweep.analysis.classify import classify
from fibersweep.analysis.observables import (
    fiber_angle,
    first_contact_index,
    pass_time,
    take,
    thin_indices,
)
from fibersweep.config.fiber import FiberSettings
from fibersweep.fiber.case import Outcome, Placed
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.kernel.bundles import build_kernel
from fibersweep.fiber.models.deformation import deformation
from fibersweep.fiber.models.spacing import offsets
from fibersweep.fiber.result import FiberStart, RunResult
from fibersweep.fiber.setup import Setup, prepare
from fibersweep.flow.field import FlowField

__all__ = ["CHANNEL", "ChannelCase"]

log = logging.getLogger(__name__)


class ChannelCase:
    """One fiber past the pillar of a channel's :class:`~fibersweep.flow.field.FlowField`."""

    name = "channel"

    def accepts(self, field) -> bool:
        """Any field no other case takes (the channel's, or an idealised test flow)."""
        return True

    def place(
        self,
        field: FlowField,
        settings: FiberSettings,
        start: FiberStart,
        rng: np.random.Generator,
        *,
        mode: int = 0,
        t_stop: float = math.nan,
    ) -> Placed:
        """Apply the effects, check the start, build the kernel (see the module docstring)."""
        setup = prepare(field, settings, start, rng)
        k = build_kernel(setup, mode=mode, t_stop=t_stop)
        return Placed(k, setup.x0, setup.y0_abs, setup.th0, setup.n, setup.effects.random, setup)

    def measure(
        self,
        placed: Placed,
        field: FlowField,
        settings: FiberSettings,
        start: FiberStart,
        out: Outcome,
    ) -> RunResult:
        """Classify and report; the effects' report hooks see ``start`` and ``field`` as
        given (the effects' own start and field are the placed run's)."""
        setup: Setup = placed.state
        result = _result(setup, placed, out)
        return setup.effects.result(result, start, field.geometry)


def _result(setup: Setup, placed: Placed, out: Outcome) -> RunResult:
    st = setup.settings
    geo = setup.field.geometry
    rec, beads, code = out.rec, out.beads, out.code
    traj = R.trajectory_from_record(rec, beads)
    common = dict(
        start=setup.start,
        n_steps=out.integrator.steps(placed.kernel, rec),
        wall_time=out.wall,
        model=st.model,
        integrator=st.resolved_integrator,
        n_beads=setup.n,
        min_clearance=float(np.min(rec[:, R.MIN_DIST]) - st.bead_radius),
        x_f=float(traj.x[-1]),
        y_f=float(traj.y[-1]),
        theta_f=float(traj.theta[-1]),
        t_end=float(traj.t[-1]),
    )
    if beads is not None and len(beads):
        common.update(
            deformation(
                beads,
                rec[:, R.CONTACT],
                setup.pillar.vertices,
                setup.pillar.circle,
                setup.pillar.r_cut,
                st.bead_radius,
                st.young_modulus,
                st.bead_spacing,
            )
        )
    k = first_contact_index(traj)
    if k is not None:
        common.update(
            contact=True,
            theta_c=fiber_angle(float(traj.theta[k])),
            y_c=float(geo.y_over_h(rec[k, R.CY])),
            t_contact=float(traj.t[k]),
        )
    common["t_pass"] = pass_time(traj, setup.pillar.x_max, setup.u_center)
    if st.record.trajectories:
        idx = thin_indices(traj, st.record.samples, setup.u_center, st.classify)
        kept = take(traj, idx)
        if st.record.all_beads and kept.beads is None:
            s = offsets(setup.n, st.bead_radius, st.bead_spacing)
            th = rec[idx, R.TH]
            bx = rec[idx, R.XC][:, None] + np.cos(th)[:, None] * s[None, :]
            by = rec[idx, R.YC][:, None] + np.sin(th)[:, None] * s[None, :]
            kept = dataclasses.replace(kept, beads=np.stack([bx, by], -1))
        elif not st.record.all_beads and kept.beads is not None:
            kept = dataclasses.replace(kept, beads=None)
        common["trajectory"] = kept
    if code < 0:
        return RunResult(status="failed", reason=R.STOP_REASONS[code], **common)
    cls = classify(traj, geo, setup.u_center, st.classify)
    if code == R.TRAPPED and cls != "Trapping":  # pragma: no cover - same rule both sides
        log.warning("kernel trap rule and classify() disagree (%s)", cls)
    if not cls:
        return RunResult(status="failed", reason="unclassified", **common)
    delta = math.nan
    if cls != "Trapping":
        delta = (float(traj.y[-1]) - setup.y0_abs) / geo.pillar_height
    return RunResult(status="ok", cls=cls, delta=delta, **common)


#: The channel case (the last the run path asks: it takes any field).
CHANNEL = ChannelCase()
