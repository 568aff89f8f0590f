"""--where selection (pandas query), the trajectory overlay and the animation of one run."""

from __future__ import annotations

import pandas as pd
import pytest
from _results_folder import refined_folder
from typer.testing import CliRunner

from fibersweep.cli import app
from fibersweep.errors import InputError
from fibersweep.plots.subset import quote_columns, select_runs


def _runs():
    return pd.DataFrame({"id": ["a", "b", "c"], "y0": [0.2, 0.35, 0.5],
                         "class": ["Below", "Trapping", "Trapping"],
                         "fiber.effects.friction": [0.0, 0.3, 0.3]})  # fmt: skip


def test_where_follows_pandas_query_with_bare_column_names():
    runs = _runs()
    assert list(select_runs(runs, 'y0 > 0.3 and class == "Trapping"')["id"]) == ["b", "c"]
    assert list(select_runs(runs, "fiber.effects.friction < 0.1")["id"]) == ["a"]
    assert list(select_runs(runs, "`class` != 'Below' and y0 < 0.4")["id"]) == ["b"]
    assert list(select_runs(runs, "class in ['Below']")["id"]) == ["a"]
    assert len(select_runs(runs, None)) == 3
    # names inside strings and longer names are left alone
    cols = ["class", "a.b"]
    assert quote_columns("class == 'class' and a.bc > 1", cols) == (
        "`class` == 'class' and a.bc > 1"
    )


@pytest.mark.parametrize(
    ("where", "message"),
    [
        ("y0 >> 0.3", "--where 'y0 >> 0.3'"),
        ("y0 >", "SyntaxError"),
        ("foo > 1", "columns: id, y0"),
        ("y0 + 1", "not a condition"),
        ("y0 > 5", "no run matches"),
        ("class > 1", "TypeError"),
    ],
)
def test_bad_where_is_an_input_error(where, message):
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(">", ">")):
        select_runs(_runs(), where)


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return refined_folder(tmp_path_factory.mktemp("sweep"))


def test_plot_tracks_of_a_subset(folder, tmp_path):
    out = tmp_path / "t.png"
    where = 'y0 > 0.3 and class != "Below"'
    r = CliRunner().invoke(app, ["plot-tracks", str(folder), "--where", where, "-o", str(out)])
    assert r.exit_code == 0, r.output
    assert out.stat().st_size > 10_000
    r = CliRunner().invoke(app, ["plot-tracks", str(folder), "--where", "y0 >"])
    assert r.exit_code == 2 and "error: --where 'y0 >'" in r.output


def test_animation_writes_a_gif_of_the_run(folder, tmp_path):
    from PIL import Image

    from fibersweep.sweep.store import read_runs

    runs = read_runs(folder)
    rid = runs.loc[runs["class"] == "Pole-vaulting", "id"].iloc[0]
    out = tmp_path / "a.gif"
    args = ["animate", str(folder), rid[:10], "-o", str(out), "--frames", "12"]
    r = CliRunner().invoke(app, args)
    assert r.exit_code == 0, r.output
    with Image.open(out) as im:
        assert im.n_frames >= 10
        im.seek(0)
        first = im.convert("RGB").tobytes()
        im.seek(im.n_frames - 1)
        assert im.convert("RGB").tobytes() != first  # the fiber moved
    r = CliRunner().invoke(app, ["animate", str(folder), rid[:10], "-o", str(tmp_path / "a.avi")])
    assert r.exit_code == 2 and ".gif" in r.output
    r = CliRunner().invoke(app, ["animate", str(folder), "zzzz"])
    assert r.exit_code == 2 and "no such run" in r.output


def test_mp4_needs_ffmpeg(folder, tmp_path):
    from matplotlib.animation import FFMpegWriter

    from fibersweep.sweep.store import read_runs

    rid = read_runs(folder)["id"].iloc[0]
    out = tmp_path / "a.mp4"
    r = CliRunner().invoke(app, ["animate", str(folder), rid, "-o", str(out), "--frames", "4"])
    if FFMpegWriter.isAvailable():
        assert r.exit_code == 0 and out.stat().st_size > 0, r.output
    else:
        assert r.exit_code == 2 and "needs the ffmpeg program" in r.output


def test_animation_of_a_flexible_fiber_draws_every_bead_or_refuses(tmp_path):
    """A bead-spring run animates through its stored beads; without them it is refused with
    the way to keep them, never drawn as the chord between its ends."""
    import numpy as np

    from fibersweep.plots.shapes import ShapeNotStored
    from fibersweep.plots.tracks import _shapes, animate_run
    from fibersweep.units import Geometry

    geo = Geometry()
    xb, yb = geo.base_center
    n, m = 6, 10
    xs = xb - 60.0 + 12.0 * np.arange(m)
    s = np.linspace(-10, 10, n)
    beads = [np.column_stack([x + s, yb + 50 + 0.1 * s**2]).ravel().tolist() for x in xs]
    samples = pd.DataFrame({"id": "r", "sample": np.arange(m), "t": np.linspace(0, 1, m),
                            "x": xs, "y": yb + 55.0, "head_x": xs + 10, "head_y": yb + 60.0,
                            "tail_x": xs - 10, "tail_y": yb + 60.0, "beads": beads})  # fmt: skip
    run = pd.Series({"id": "r", "theta0": 0.0, "y0": 0.5, "length": 1.0, "class": "Above",
                     "status": "ok", "model": "bead-spring-ros2", "n_beads": n})  # fmt: skip
    shapes = _shapes(run, samples, geo, np.arange(m))
    assert all(len(p) == n for p in shapes)
    assert animate_run(run, samples, geo, tmp_path / "f.gif", frames=4).stat().st_size > 0
    with pytest.raises(ShapeNotStored, match="all_beads"):
        animate_run(run, samples.drop(columns="beads"), geo, tmp_path / "g.gif", frames=4)
