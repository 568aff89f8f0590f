"""A pillar array's critical length located by `fibersweep run` with sweep.refine.

Random starts (sweep.random) in a dx = 4 µm cell: the refinement bisects the lengths
whose mean displacement fraction lies on either side of 1/2 until the bracket is within
the tolerance; each new length gets its seeded starts as if it had been in the grid; a
second run resumes without running anything.

The grid's two lengths lie far on either side of 1/2, so the bracket exists on any
machine: with a row shift of 1/4 and 8 rows (two whole zigzag periods), 24 random
spheres (4 µm) gave a mean f of 0.004 (sd 0.02) and 24 fibers of 80 µm 0.96 (sd 0.07),
so the mean of 6 lies 50 and 15 standard errors from 1/2. (At a shift of 0.1 and 6
rows, fewer than one zigzag period, every length from 4 to 60 µm gave f between 0.38
and 0.66: no length was clearly on either side.)
"""

from __future__ import annotations

import json

from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.sweep.store import read_runs

CONFIG = """\
flow:
  dx: 4.0
  array: {{shift: 0.25}}
fiber:
  model: rigid
  array_rows: 8
sweep:
  length: [4.0, 80.0]
  theta0: [-10.0, 10.0]
  y0: [0.0, 1.0]
  random: {{count: 6, seed: 0}}
  refine: {{axes: [length], tolerance: {{length: 10.0}}, max_runs: 60}}
run:
  workers: 2
  output: {out}
  cache_dir: {cache}
"""


def test_refinement_brackets_the_critical_length_and_resumes(tmp_path, flow_cache_dir):
    out = tmp_path / "res"
    cfg = tmp_path / "array.yaml"
    cfg.write_text(CONFIG.format(out=out, cache=flow_cache_dir))
    res = CliRunner().invoke(app, ["run", str(cfg)])
    assert res.exit_code == 0, res.output
    runs = read_runs(out)
    lengths = sorted(runs["length"].unique())
    assert lengths[0] == 4.0 and lengths[-1] == 80.0 and len(lengths) > 2
    assert (runs.groupby("length").size() == 6).all()  # every length its 6 starts
    # the located bracket: neighbouring lengths within 10 µm, means on either side of 1/2
    f = runs[runs["mode"] != "trapped"].groupby("length")["fraction"].mean()
    cross = [(a, b) for a, b in zip(f.index[:-1], f.index[1:], strict=True)
             if (f[a] - 0.5) * (f[b] - 0.5) < 0]  # fmt: skip
    assert f.iloc[0] < 0.2 and f.iloc[-1] > 0.8, f  # the grid's ends, far from 1/2
    assert cross and all(b - a <= 10.0 for a, b in cross), f
    man = json.loads((out / "manifest.json").read_text())
    assert man["refinement"]["stopped"] == "located" and man["refinement"]["runs"] == len(
        runs
    ) - 12
    again = CliRunner().invoke(app, ["run", str(cfg)])
    assert again.exit_code == 0 and "nothing to run" in again.output, again.output
    assert len(read_runs(out)) == len(runs)


def test_refining_random_starts_in_a_channel_is_refused(tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text(
        "sweep:\n  y0: [0.1, 0.5]\n  length: [1.0]\n  random: {count: 2}\n"
        "  refine: {axes: [length], tolerance: {length: 0.1}, max_runs: 10}\n"
    )
    res = CliRunner().invoke(app, ["run", str(cfg)])
    assert res.exit_code == 2 and "sweep.refine" in res.output, res.output
