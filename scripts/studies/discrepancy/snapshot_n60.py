"""A single-pillar discrepancy snapshot at N = 60: regenerate or check it in one command.

Synthesises 60 fibers on the study field (the SPEC channel at dx = 4 µm, the
tests' coarse field) with inlet_speed = 0.08 hidden, seed 6060, runs the workflow
with a reduced plan (3 copies, power analysis and what-to-measure-next off, three
library effects) and writes what a verdict is made of: the verdict's kind, names
and fitted values, the fits, the refits' intervals, each held-out evaluation and
the gap per observable, every float at full precision (JSON's shortest repr that
round-trips). Whoever changes a shared code path of the workflow shows single-pillar
verdicts unchanged by a bit-identical snapshot
(``tests/validation/test_discrepancy_array_hidden.py`` compares it). A change that is
meant to alter the numbers (fit.py, estimate.py) regenerates it with ``--write``.

Usage (about 1-3 minutes on the 2 loaded cores)::

    python scripts/studies/discrepancy/snapshot_n60.py --write   # regenerate tests/data/...
    python scripts/studies/discrepancy/snapshot_n60.py           # compare with the stored one
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from fibersweep.config.fiber import FiberSettings
from fibersweep.discrepancy.schema import validate_measured
from fibersweep.discrepancy.synth import synthesize
from fibersweep.discrepancy.workflow import DiscrepancySettings, run_discrepancy

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import BOX, REPO, study_field  # noqa: E402

SNAPSHOT = REPO / "tests" / "data" / "discrepancy_snapshot_n60.json"
N = 60
SEED = 6060
HIDDEN = {"inlet_speed": 0.08}
SETTINGS = dict(
    copies=3, fit_copies=2, candidates=2, fit_evals=4, refits=1, n_perm=1999,
    power_fibers=0, next_copies=0, effects=("inlet_speed", "friction", "pillar_scale"),
)  # fmt: skip


def _plain(x: Any) -> Any:
    """JSON-ready: floats as Python floats (repr round-trips), arrays as lists, keys as str."""
    if isinstance(x, dict):
        return {str(k): _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return _plain(x.tolist())
    if isinstance(x, (np.floating, float)):
        return float(x)
    if isinstance(x, (np.integer, int)) and not isinstance(x, bool):
        return int(x)
    if isinstance(x, np.bool_):
        return bool(x)
    return x


def snapshot(workers: int = 1) -> dict[str, Any]:
    """Run the N = 60 case and return its snapshot (see the module docstring)."""
    field = study_field()
    table, _ = synthesize(field, FiberSettings(), BOX, N, HIDDEN, seed=SEED, workers=workers,
                          progress=False)  # fmt: skip
    data = validate_measured(table)
    settings = DiscrepancySettings(seed=SEED, workers=workers, **SETTINGS)
    res = run_discrepancy(data, field, FiberSettings(), settings, progress=False)
    v = res.verdict
    return _plain({
        "case": {"n": N, "seed": SEED, "hidden": HIDDEN, "settings": SETTINGS},
        "verdict": {"kind": v.kind, "effects": v.effects, "observable": v.observable,
                    "region": v.region, "alternatives": list(v.alternatives)},
        "fits": [{"name": f.name, "value": f.value, "loss": f.loss, "loss0": f.loss0,
                  "evaluations": f.evaluations} for f in res.fits],
        "intervals": res.extra.get("intervals", {}),
        "fold_values": res.extra.get("fold_values", {}),
        "heldout": [{"name": h.name, "value": h.value, "improvement": h.improvement,
                     "p_value": h.p_value, "p_holm": h.p_holm, "significant": h.significant,
                     "explains": h.explains} for h in res.heldout],
        "gap": {k: {"excess": g.excess, "p_holm": g.p_holm, "bias_z": g.bias_z}
                for k, g in res.gap.gaps.items()},
        "simulations": res.simulations,
    })  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--write", action="store_true", help=f"write {SNAPSHOT.name}")
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--out", type=Path, default=SNAPSHOT)
    args = ap.parse_args(argv)
    snap = snapshot(args.workers)
    text = json.dumps(snap, indent=1, sort_keys=True) + "\n"
    if args.write:
        args.out.write_text(text)
        print(f"wrote {args.out}: {snap['verdict']['kind']} {snap['verdict']['effects']}")
        return 0
    stored = args.out.read_text()
    same = stored == text
    print(f"{'bit-identical' if same else 'DIFFERS from'} {args.out}: {snap['verdict']['kind']}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
