"""Steps of a rigid run against the contact gap δ_r, what bounds them, and the runs' outcomes.

    python3 scripts/benchmarks/near_contact_steps.py [--cache DIR] [--gaps 0.3 0.1 0.05 0.02]
        [--example-gaps 0.05] [--json OUT] [--compare OLD.json NEW.json]

Cases: the channel's rigid fiber with contact at the apex (configs' defaults, y0/h 0.45)
and a sphere (a = 6 µm) through 20 rows of the circle array at ε = 0.1 (as
``bench_near_wall.py``), each with the chi law and no effect ("off"), with ``near_wall``
alone (chi law), and with all the near-contact physics on (``near_wall`` = 1, ``faxen`` =
1, curvature local, r_c 1 µm) at each gap; and, all on at each ``--example-gaps``, the two
worked examples of the source (configs/paper.yaml) and spheres of a = 5 and 7 µm. Per run:
steps, the steps inside the contact layer (centre closer than R_ref to the outline), the
steps whose Δt is below the displacement bound (so the contact stiffness set it; read from
the record: Δt < 0.98 of min(disp / speed, dt_max)), the CPU time, and the outcome (class,
δ [h_obs], and in the array the displacement fraction and mode).

``--json`` writes the outcomes; ``--compare`` prints the largest differences between two
such files (the same cases run on two versions of the code).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.config.loading import load_config
from fibersweep.fiber.kernel import record as R
from fibersweep.fiber.models.registry import integrator_of
from fibersweep.fiber.result import FiberStart
from fibersweep.fiber.run import _place, simulate
from fibersweep.flow.cache import get_flow_field

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_near_wall import cases  # noqa: E402  (the same cases)

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ((-3.7, 0.373, 0.82), (8.0, 0.351, 0.75))  # the source's (θ0, y0/h, L/l_obs)


def variant(base: FiberSettings, gap: float | None, near_wall: bool, all_on: bool) -> FiberSettings:
    """``base`` with the gap law (``gap`` µm; None: chi) and the effects named."""
    c = base.contact.model_dump()
    eff = dict(base.effects)
    if gap is not None:
        c.update(law="gap", gap_um=gap)
    if all_on:
        c.update(curvature="local", corner_radius=1.0)
        eff["faxen"] = 1.0
    if near_wall or all_on:
        eff["near_wall"] = 1.0
    return FiberSettings.model_validate({**base.model_dump(), "contact": c, "effects": eff})


def bounds(field, st: FiberSettings, start: FiberStart) -> tuple[int, int, int]:
    """(steps, steps in the contact layer, steps below the displacement bound) of one run."""
    _, placed = _place(field, st, start, np.random.default_rng(0))
    rec, _, _ = integrator_of(st).integrate(placed.kernel, placed.x0, placed.y0, placed.th0, None)
    k = placed.kernel
    p = k.params
    s = k.body.s
    half = 0.5 * (s[-1] - s[0])
    dt = np.diff(rec[:, R.T])
    r = rec[:-1]
    speed = r[:, R.COM_SPEED] + np.abs(r[:, R.OM]) * half + 1e-12
    free = r[:, R.MIN_DIST] - k.pillar.r_cut
    disp = np.minimum(p.max_disp, np.maximum(p.contact_disp, 0.5 * free))
    dt_disp = np.minimum(disp / speed, p.dt_max)
    return len(dt), int((free < 0).sum()), int((dt < 0.98 * dt_disp).sum())


def outcome(label: str, field, st: FiberSettings, start: FiberStart) -> dict:
    """One run's steps, their bounds, CPU time (minimum of 2) and outcome."""
    simulate(field, st, start)  # compile
    cpu = math.inf
    for _ in range(2):
        t0 = time.process_time()
        res = simulate(field, st, start)
        cpu = min(cpu, time.process_time() - t0)
    n, layer, stiff = bounds(field, st, start)
    out = {"case": label, "steps": res.n_steps, "in_layer": layer, "stiffness_bound": stiff,
           "cpu_ms": round(cpu * 1e3, 1), "cls": res.cls, "delta": res.delta,
           "fraction": res.fraction, "mode": res.mode}  # fmt: skip
    print(json.dumps(out), flush=True)
    return out


def run_all(cache: str, gaps: list[float], example_gaps: list[float]) -> list[dict]:
    """Every case of the module docstring."""
    out = []
    (_, channel, rigid, apex), (_, cell, sphere, s_start) = cases(cache)[1:]
    for name, field, base, start in (("apex", channel, rigid, apex), ("sphere a=6", cell, sphere,
                                                                      s_start)):  # fmt: skip
        out.append(outcome(f"{name}, off", field, base, start))
        out.append(outcome(f"{name}, near_wall chi", field, variant(base, None, True, False),
                           start))  # fmt: skip
        for g in gaps:
            out.append(outcome(f"{name}, all on, gap {g:g}", field, variant(base, g, True, True),
                               start))  # fmt: skip
    paper = load_config(ROOT / "configs" / "paper.yaml")
    pfield, _ = get_flow_field(paper.flow.model_copy(update={"dx": 4.0}), cache)
    for g in example_gaps:
        on = variant(paper.fiber, g, True, True)
        for th, y0, length in EXAMPLES:
            out.append(outcome(f"example ({th:g}, {y0:g}, {length:g}), all on, gap {g:g}",
                               pfield, on, FiberStart(th, y0, length)))  # fmt: skip
        for a in (5.0, 7.0):
            st = variant(sphere.model_copy(update={"bead_radius": a}), g, True, True)
            out.append(outcome(f"sphere a={a:g}, all on, gap {g:g}", cell, st,
                               FiberStart(0.0, 0.37, 2 * a)))  # fmt: skip
    return out


def _diff(x: float | None, y: float | None) -> float:
    """|x − y|, 0 where either is missing (NaN: a channel run's fraction, an array run's δ)."""
    if x is None or y is None or math.isnan(x) or math.isnan(y):
        return 0.0
    return abs(x - y)


def compare(old_path: str, new_path: str) -> None:
    """Print each case's steps and outcome in both files, and the largest differences."""
    old = {r["case"]: r for r in json.loads(Path(old_path).read_text())}
    new = {r["case"]: r for r in json.loads(Path(new_path).read_text())}
    worst_d = worst_f = 0.0
    same_cls = True
    for case, a in old.items():
        b = new[case]
        dd = _diff(a["delta"], b["delta"])
        ff = _diff(a["fraction"], b["fraction"])
        worst_d = max(worst_d, dd)
        worst_f = max(worst_f, ff)
        same_cls &= a["cls"] == b["cls"] and a["mode"] == b["mode"]
        print(f"{case:45s} steps {a['steps']:7d} -> {b['steps']:7d}  cpu {a['cpu_ms']:7.1f} -> "
              f"{b['cpu_ms']:7.1f} ms  {a['cls'] or a['mode']} -> {b['cls'] or b['mode']}  "
              f"|Δδ| {dd:.4f}  |Δf| {ff:.4f}")  # fmt: skip
    print(f"largest |Δδ| {worst_d:.4f} h_obs, |Δfraction| {worst_f:.4f}, classes and modes "
          f"{'equal' if same_cls else 'DIFFER'}")  # fmt: skip


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", default=".fibersweep-cache")
    ap.add_argument("--gaps", type=float, nargs="+", default=[0.3, 0.1, 0.05, 0.02])
    ap.add_argument("--example-gaps", type=float, nargs="+", default=[0.05],
                    help="gaps of the worked examples and the spheres a = 5, 7 µm")  # fmt: skip
    ap.add_argument("--json", help="write the outcomes here")
    ap.add_argument("--compare", nargs=2, metavar=("OLD", "NEW"))
    args = ap.parse_args()
    if args.compare:
        compare(*args.compare)
        return
    out = run_all(args.cache, args.gaps, args.example_gaps)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
