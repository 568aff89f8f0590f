"""The flow solver reports its progress to a callback, and only inside ``on_progress``."""

from __future__ import annotations

import math

from fibersweep.config.flow import FlowSettings, GeometrySettings
from fibersweep.flow.lbm import solve_lattice
from fibersweep.flow.progress import on_progress

# A short duct (no pillar) converges in a few hundred steps at dx = 4 µm.
DUCT = FlowSettings(
    geometry=GeometrySettings(width=80.0, depth=40.0, length=80.0, pillar_height=20.0), dx=4.0
)


def test_progress_reports_every_check_up_to_the_final_state():
    seen = []
    with on_progress(seen.append):
        sol = solve_lattice(DUCT, pillar=False)
    rep = sol.report
    assert seen[0].steps == 0 and math.isinf(seen[0].residual)  # before the first step
    steps = [p.steps for p in seen]
    assert steps == sorted(steps) and len(set(steps)) == len(steps)
    last = seen[-1]
    # the last report is the solver's own final state
    assert last.steps == rep.steps and last.residual == rep.residual
    assert (last.residual < DUCT.tolerance) == rep.converged
    assert all(p.dx == DUCT.dx and p.tolerance == DUCT.tolerance for p in seen)
    assert all(p.cells == sol.grid.cells for p in seen)


def test_no_callback_outside_the_block():
    seen = []
    with on_progress(seen.append):
        pass
    solve_lattice(DUCT, pillar=False)
    assert seen == []


def test_finished_marks_the_last_report_of_a_solve():
    """A bar closes on ``finished``: true on the solver's final report only (converged or
    out of steps), never on the first (step 0) one."""
    seen = []
    with on_progress(seen.append):
        solve_lattice(DUCT, pillar=False)
    assert [p.finished for p in seen] == [False] * (len(seen) - 1) + [True]
    capped = DUCT.model_copy(update={"max_steps": 200, "check_every": 100})
    seen = []
    with on_progress(seen.append):
        solve_lattice(capped, pillar=False)
    assert seen[-1].steps == 200 and seen[-1].finished and not seen[-2].finished
