"""Coverage of the refit's 95 % interval per number of fibers and per effect, read offline.

Reads the single-effect and declared-candidate data sets of
``scripts/studies/discrepancy/study_coverage.py`` (one folder per N; each JSON keeps
the pooled refit's per-fiber losses, ``profile``) and reads each refit's interval
again from them with :func:`fibersweep.discrepancy.estimate.score_interval` (the
bootstrap over fibers of the mean loss's minimiser; ``--n-boot`` resamples). The
table gives, per N and effect, the data sets whose interval holds the truth with
their Wilson 95 % interval, the mean width relative to the truth, the open ends
and whether the interval stored by the run agrees (the run's interval step
evaluated its ends with the code of its day)::

    python scripts/studies/discrepancy/read_intervals.py results/interval_cov/n20 \
        results/interval_cov/n60 results/interval_cov/n200

A data set without a significant gap (nothing fitted) is counted under "no gap"
and left out of the coverage: it is conditional on the right name.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from fibersweep.discrepancy.estimate import N_BOOT, Fit, score_interval

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from common import wilson  # noqa: E402


def load(folder: Path) -> list[dict]:
    """Every single-effect or declared data set under ``folder`` (fitted or not)."""
    rows = []
    for kind in ("single", "declared"):
        rows += [json.loads(p.read_text()) for p in sorted(folder.glob(f"{kind}/seed*.json"))]
    return rows


def reread(row: dict, n_boot: int) -> dict | None:
    """The refit's interval read again from its stored per-fiber losses (None: no fit)."""
    if not row["rows"] or "profile" not in row:
        return None
    x = row["rows"][0]
    prof = tuple((float(v), np.asarray(loss, dtype=float)) for v, loss in row["profile"])
    disp = tuple((float(v), np.asarray(d, dtype=float)) for v, d in row.get("dispersion", []))
    fit = Fit(x["effect"], float(x["value"]), 0.0, 0.0, (), prof, disp)
    lo, hi, open_lo, open_hi = score_interval(fit, n_boot=n_boot)
    truth = float(x["truth"])
    return {"effect": x["effect"], "n": row["n"], "truth": truth, "lo": lo, "hi": hi,
            "open": open_lo or open_hi, "covered": bool(lo <= truth <= hi),
            "as_run": bool(x["covered"]), "width": (hi - lo) / abs(truth)}  # fmt: skip


def table(folders: list[Path], n_boot: int) -> str:
    lines = ["| N | effect | data sets (no gap) | covered k/n | coverage [Wilson 95 %] "
             "| mean width / truth | open ends | covered as run |",
             "|---|---|---|---|---|---|---|---|"]  # fmt: skip
    allx: list[dict] = []
    for folder in folders:
        rows = load(folder)
        if not rows:
            continue
        n = rows[0]["n"]
        xs = [r for r in (reread(row, n_boot) for row in rows) if r is not None]
        allx += xs
        effects = list(dict.fromkeys(next(iter(r["truth"])) for r in rows))
        for label in [*effects, "all"]:
            sets = [r for r in rows if label == "all" or label in r["truth"]]
            got = [x for x in xs if label == "all" or x["effect"] == label]
            nogap = sum(not r["rows"] for r in sets)
            if not got:
                lines.append(f"| {n} | {label} | {len(sets)} ({nogap}) | 0/0 | | | | |")
                continue
            k = sum(x["covered"] for x in got)
            lo, hi = wilson(k, len(got))
            lines.append(
                f"| {n} | {label} | {len(sets)} ({nogap}) | {k}/{len(got)} | "
                f"{k / len(got):.2f} [{lo:.2f}, {hi:.2f}] | "
                f"{np.mean([x['width'] for x in got]):.2f} | {sum(x['open'] for x in got)} | "
                f"{sum(x['as_run'] for x in got)}/{len(got)} |"
            )
    if allx:
        k = sum(x["covered"] for x in allx)
        lo, hi = wilson(k, len(allx))
        lines.append(f"| all | all | | {k}/{len(allx)} | {k / len(allx):.2f} [{lo:.2f}, "
                     f"{hi:.2f}] | | | |")  # fmt: skip
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path, help="study_coverage outputs, one per N")
    ap.add_argument("--n-boot", type=int, default=N_BOOT, help="bootstrap resamples")
    args = ap.parse_args()
    print(table(args.folders, args.n_boot))


if __name__ == "__main__":
    main()
