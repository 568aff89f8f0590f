"""Progress bars: plain lines at tqdm's pace into a file, a live bar on a terminal,
and a bar that stops early ends at its real count."""

from __future__ import annotations

import io

import pytest
from tqdm import tqdm

from fibersweep.progressbar import LINE_INTERVAL_S, LineTqdm, finish, progress_bar


class _Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def _line_bar(total, **kw):
    out = io.StringIO()
    bar = progress_bar(total=total, desc="runs", unit="run", file=out, **kw)
    clock = _Clock()
    bar._time = clock  # tqdm's own clock hook: the bar's time comes from here
    bar.start_t = bar.last_print_t = bar._last_line_t = clock()
    return bar, out, clock


def test_a_file_gets_plain_lines_about_every_ten_seconds():
    bar, out, clock = _line_bar(100)
    assert isinstance(bar, LineTqdm)
    for _ in range(60):  # one run per second for a minute
        clock.t += 1.0
        bar.update(1)
    bar.close()
    text = out.getvalue()
    assert "\r" not in text and "\x1b" not in text  # no carriage return, no cursor escape
    lines = text.splitlines()
    assert lines[0].startswith("runs:") and "0/100" in lines[0]  # the start
    assert "60/100" in lines[-1]  # the final state, written once at close
    updates = lines[1:-1]
    # tqdm refreshes when mininterval has passed at an update: 60 s / 10 s -> 5 or 6 lines
    # (the last one may coincide with the final state, which is then not repeated)
    assert 5 <= len(updates) + 1 <= 7, lines
    assert LINE_INTERVAL_S == 10.0
    assert len(set(lines)) == len(lines)  # never the same line twice


def test_log_lines_between_refreshes_do_not_repeat_the_bar():
    bar, out, clock = _line_bar(10)
    clock.t += 11
    bar.update(1)
    for k in range(3):  # tqdm.write redraws every bar after the message
        tqdm.write(f"message {k}", file=out)
    bar.close()
    lines = out.getvalue().splitlines()
    assert [ln for ln in lines if ln.startswith("message")] == [f"message {k}" for k in range(3)]
    assert sum("1/10" in ln for ln in lines) == 1


def test_finish_ends_a_bar_that_stopped_early_at_its_real_count():
    bar, out, clock = _line_bar(1150)
    clock.t += 20
    bar.update(80)
    finish(bar)
    last = out.getvalue().splitlines()[-1]
    assert "80/80" in last and "1150" not in last and "100%" in last


def test_user_tqdm_environment_wins(monkeypatch):
    monkeypatch.setenv("TQDM_MININTERVAL", "60")
    out = io.StringIO()
    bar = progress_bar(total=3, file=out)
    # our 10 s default is not passed, so tqdm's own TQDM_MININTERVAL (read at import) or its
    # default applies: never ours
    assert bar.mininterval != LINE_INTERVAL_S
    bar.close()


@pytest.mark.parametrize("tty", [True, False])
def test_the_form_follows_the_stream(tty):
    class Stream(io.StringIO):
        def isatty(self) -> bool:
            return tty

    bar = progress_bar(total=2, file=Stream())
    assert isinstance(bar, LineTqdm) is (not tty)
    assert bar.mininterval == (0.2 if tty else LINE_INTERVAL_S)
    bar.close()


def test_a_jupyter_kernel_gets_tqdm_auto(monkeypatch):
    """Inside a kernel (IPython's config holds IPKernelApp) the bar is tqdm.auto's."""
    import sys
    import types

    from tqdm.auto import tqdm as auto_tqdm

    class Shell:
        config = {"IPKernelApp": {}}

    fake = types.ModuleType("IPython")
    fake.get_ipython = lambda: Shell()
    monkeypatch.setitem(sys.modules, "IPython", fake)
    bar = progress_bar(total=2)
    try:
        assert isinstance(bar, auto_tqdm) and not isinstance(bar, LineTqdm)
    finally:
        bar.close()


def test_rate_and_estimate_start_after_the_workers_start_up():
    """A first run slowed by compiling the kernels (60 s) does not make the estimate."""
    from fibersweep.progressbar import WARMING_FORMAT, WarmingBar

    out = io.StringIO()
    clock = _Clock()
    bar = WarmingBar(100, warm=2, note="workers starting", unit="run", file=out, smoothing=0.1)
    inner = bar._bar
    inner._time = clock
    inner.start_t = inner.last_print_t = inner._last_line_t = clock()
    assert inner.bar_format == WARMING_FORMAT and "workers starting" in out.getvalue()
    clock.t += 60.0  # both workers compile, then finish their first run
    bar.update(1)
    clock.t += 0.5
    bar.update(1)
    assert "<" not in out.getvalue() and "run/s" not in out.getvalue()  # no estimate yet
    for _ in range(40):  # then one run every 0.5 s
        clock.t += 0.5
        bar.update(1)
    bar.refresh()
    line = out.getvalue().splitlines()[-1]
    assert inner.bar_format is None
    rate = float(line.split("run/s")[0].split()[-1].rstrip(","))
    assert rate == pytest.approx(2.0, rel=0.05), line  # the rate of the runs, not 42/80 s
    left = line.split("<")[1].split(",")[0]  # 58 runs at 2/s: 29 s
    assert left == "00:29", line


def test_a_warming_bar_drops_its_note_once_warm_and_forwards_its_length():
    """The start-up note holds until ``warm`` units are done; a length set on the
    wrapper is the bar's (the discrepancy simulator grows and ends it so)."""
    from fibersweep.progressbar import WarmingBar

    out = io.StringIO()
    bar = WarmingBar(4, warm=2, note="workers starting", file=out)
    bar.update(1)
    assert bar.postfix == "workers starting"
    bar.update(1)
    assert not bar.postfix
    bar.total = 6
    assert bar._bar.total == 6
    finish(bar)
    assert bar._bar.total == 2  # ended at its real count


def test_a_disabled_warming_bar_counts_without_drawing(monkeypatch):
    """TQDM_DISABLE=1 (or disable=True): updates past the warm-up never touch a format."""
    from fibersweep.progressbar import WarmingBar

    bar = WarmingBar(4, warm=1, note="workers starting", disable=True)
    for _ in range(4):
        bar.update(1)
    bar.total = 5
    finish(bar)
