"""Does the true model leave a gap? The gap test against copies made with the hidden model.

Synthesises ``--n`` fibers with the hidden effects (and fiber model) in a start box,
makes 8 jittered copies of every fiber with exactly that model (the copy maker
of the workflow, its own seed), and runs the workflow's gap test
(:func:`fibersweep.discrepancy.gap.assess_gap`, Holm over every observable's score
and signed residual at α = 0.05). Under the measurement model the test rejects
in at most 5 % of data sets; more means the synthesised data and the model's
copies differ in something other than the effect (start box, noise, settings),
which no fitted value can remove.

``--box study`` is the studies' start box (θ0 −10..10°, y0 0.15..0.65, L 0.5..1.4);
``--box quick`` is ``configs/quick.yaml``'s sweep box (θ0 −8..8°, y0 0.05..0.9,
L = 1 for every fiber), the box ``fibersweep synth configs/quick.yaml`` draws from.
``--shrink`` makes the copies as the workflow does (:class:`.copies.CopyMaker`: a
start column with one true value, :func:`.copies.fixed_columns`, is copied at that
value); ``--no-shrink`` jitters every column of the measured start.

Usage::

    python scripts/studies/discrepancy/diagnose_truth_gap.py --box quick --effects \
        friction=0.36 inlet_speed=0.023 --seeds 1 2 3 4 5 6 7 8 --out results/truthgap
    python scripts/studies/discrepancy/diagnose_truth_gap.py --tabulate --out results/truthgap
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.copies import CopyMaker, NoiseModel
from fibersweep.discrepancy.gap import assess_gap, value_matrices
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.simulate import Simulator
from fibersweep.discrepancy.synth import synthesize

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import (  # noqa: E402
    BOX,
    REPO,
    parse_study,
    study_field,
    study_parser,
    wilson,
)

log = logging.getLogger("truthgap")


def quick_box() -> dict[str, tuple[float, float]]:
    """configs/quick.yaml's sweep box, the one ``fibersweep synth configs/quick.yaml`` uses."""
    from fibersweep.api.common import load_config
    from fibersweep.api.compare import sweep_box

    return sweep_box(load_config(REPO / "configs" / "quick.yaml"))


def one(args, seed: int, field) -> dict:
    effects = {k: float(v) for k, v in (e.split("=") for e in args.effects)}
    fiber = FiberSettings()
    if args.young_modulus:
        fiber = FiberSettings(model="bead-spring", integrator="ros2",
                              young_modulus=args.young_modulus)  # fmt: skip
    box = quick_box() if args.box == "quick" else BOX
    t0 = time.perf_counter()
    table, _ = synthesize(field, fiber, box, args.n, effects, seed=seed, workers=args.workers,
                          progress=False)  # fmt: skip
    data = validate_measured(table, source="truthgap")
    with Simulator(field, fiber, workers=args.workers, progress=False, tracks=False) as sim:
        maker = CopyMaker(data.starts, NoiseModel(), seed + 104729, sim)
        if not args.shrink:
            maker.fixed = {}  # the copies before fixed_columns: every column jittered
        cps = maker.copies(range(8), effects)
    values = value_matrices(data.table.reset_index(drop=True), cps, tuple(data.observed))
    g = assess_gap(values, np.random.default_rng([seed, 97]))
    return {
        "seed": seed,
        "box": args.box,
        "effects": effects,
        "young_modulus": args.young_modulus,
        "shrink": args.shrink,
        "n": len(table),
        "flagged": g.flagged,
        "score_p_holm": {n: round(x.p_holm, 4) for n, x in g.gaps.items()},
        "bias_z": {n: [round(q, 2) for q in x.bias_z] for n, x in g.gaps.items()},
        "score_z": {n: round(x.test.z, 2) for n, x in g.gaps.items()},
        "seconds": round(time.perf_counter() - t0, 1),
    }


def tabulate(out: Path) -> str:
    rows = [json.loads(p.read_text()) for p in sorted(out.glob("*.json"))]
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        key = (r["box"], json.dumps(r["effects"]), r["young_modulus"], r["shrink"])
        groups.setdefault(key, []).append(r)
    lines = [
        "| box | hidden | copies | data sets | true model leaves a gap [Wilson 95 %] "
        "| flagged | mean score z per observable |",
        "|---|---|---|---|---|---|---|",
    ]
    for (box, eff, e, shrink), rs in groups.items():
        k = sum(bool(r["flagged"]) for r in rs)
        lo, hi = wilson(k, len(rs))
        flagged = sorted({o for r in rs for o in r["flagged"]})
        names = rs[0]["score_z"]
        mz = ", ".join(f"{o} {np.mean([r['score_z'][o] for r in rs]):+.1f}" for o in names)
        hidden = eff + (f", E = {e:g} Pa" if e else "")
        how = "prior from the starts" if shrink else "jittered measured start"
        lines.append(f"| {box} | {hidden} | {how} | {len(rs)} | {k} [{lo:.2f}, {hi:.2f}] | "
                     f"{', '.join(flagged) or '–'} | {mz} |")  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = study_parser(__doc__, "results/truthgap")
    ap.add_argument("--box", choices=("study", "quick"), default="study")
    ap.add_argument("--effects", nargs="*", default=[])
    ap.add_argument(
        "--young-modulus",
        type=float,
        default=None,
        help="flexible fibers (bead-spring, ros2) of this E [Pa]",
    )
    ap.add_argument("--shrink", action=argparse.BooleanOptionalAction, default=True)
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    if (args := parse_study(ap, tabulate)) is None:
        return
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    field = study_field(args.cache)
    tag = "_".join([args.box, *args.effects, f"E{args.young_modulus or 0:g}",
                    "shrink" if args.shrink else "jitter"])  # fmt: skip
    for seed in args.seeds:
        path = out / f"{tag}_{seed}.json"
        if path.exists():
            continue
        row = one(args, seed, field)
        path.write_text(json.dumps(row, indent=1))
        log.warning("%s seed %d: flagged %s (%.0f s)", tag, seed, row["flagged"], row["seconds"])


if __name__ == "__main__":
    main()
