"""Progress bars that suit where the output goes: a terminal, a log file, a notebook.

Every bar of fibersweep (the flow solve, the sweep, the discrepancy workflow) is
made by :func:`progress_bar`, which picks one of tqdm's own front ends:

* a **terminal** (stderr is a TTY): tqdm's live bar, redrawn at most every 0.2 s;
* a **Jupyter kernel**: ``tqdm.auto`` (a widget if ipywidgets is installed);
* anything else, a **log file, a pipe, a cluster job's output**: :class:`LineTqdm`,
  the same tqdm counters written as one plain line (no carriage return, no
  cursor movement) at most every 10 s, plus the final line when the bar closes.

tqdm's own ``TQDM_*`` environment variables still apply: a value the user set
(``TQDM_MININTERVAL=60``, ``TQDM_DISABLE=1``) replaces the default chosen here.
"""

from __future__ import annotations

import os
import sys
from typing import Any

from tqdm import tqdm

__all__ = [
    "LINE_INTERVAL_S",
    "TTY_INTERVAL_S",
    "WARMING_FORMAT",
    "LineTqdm",
    "finish",
    "progress_bar",
    "start_clock",
    "WarmingBar",
]

#: Seconds between redraws of a live bar on a terminal [s].
TTY_INTERVAL_S = 0.2
#: Seconds between plain lines into a file [s] (docs/cli.md promises 10 s).
LINE_INTERVAL_S = 10.0
#: Bar format while the first units include start-up (compiling kernels): no rate, no
#: remaining time, which that start-up would make meaningless (:func:`start_clock`).
WARMING_FORMAT = "{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}{postfix}]"


class LineTqdm(tqdm):
    """tqdm that writes each refresh as a plain line, for output that is not a terminal.

    tqdm decides *when* to refresh (``mininterval``, ``miniters``), so the counters,
    rate and ETA are tqdm's; only :meth:`display` changes: it appends a line with
    a newline instead of redrawing one with ``\\r`` and cursor escapes. A redraw
    sooner than ``mininterval`` after the last line (tqdm redraws after every
    ``tqdm.write``, e.g. a log line) and a line equal to the last one are skipped.

    The bar is made with ``leave=False`` so that tqdm's ``close`` calls
    ``display(msg="")`` rather than writing its own newline; that call writes the
    final state, with the overall rate, if it was not written already.
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._last_line: str | None = None
        self._last_line_t: float | None = None
        kwargs["leave"] = False
        super().__init__(*args, **kwargs)

    def display(self, msg: str | None = None, pos: int | None = None) -> bool:
        """Write the state as a line (tqdm calls this on every refresh and at close)."""
        if msg == "":  # tqdm's close: write the final state
            self._ema_dt = lambda: None  # overall rate, as tqdm's own final line
            self._line(self.__str__())
            return False
        now = self._time()
        if self._last_line_t is not None and now - self._last_line_t < self.mininterval:
            return True  # a redraw forced between refreshes (after a log line): not a new line
        self._line(self.__str__() if msg is None else msg)
        self._last_line_t = now
        return True

    def clear(self, nolock: bool = False) -> None:
        """Nothing to clear: written lines stay."""

    def _line(self, text: str) -> None:
        if not text or text == self._last_line:
            return
        self._last_line = text
        self.fp.write(text + "\n")
        getattr(self.fp, "flush", lambda: None)()


def _in_notebook() -> bool:
    """True inside a Jupyter kernel (not a terminal IPython)."""
    shell = sys.modules.get("IPython")
    if shell is None:
        return False
    try:
        ip = shell.get_ipython()  # type: ignore[attr-defined]
    except Exception:  # an IPython that cannot tell
        return False
    return ip is not None and "IPKernelApp" in getattr(ip, "config", {})


def _tty(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def progress_bar(
    total: float | None = None,
    desc: str | None = None,
    unit: str = "it",
    file: Any = None,
    **kwargs: Any,
) -> tqdm:
    """A tqdm bar for stderr (or ``file``), in the form that suits it (module docstring).

    Parameters
    ----------
    total : float, optional
        Expected count (None: unknown, the bar shows the count and rate only).
    desc : str, optional
        Label before the counters.
    unit : str
        Unit of the count, e.g. ``"run"`` or ``" steps"``.
    file : file-like, optional
        Where the bar is written (default ``sys.stderr`` at call time).
    **kwargs
        Further tqdm options (``smoothing``, ``postfix``...); they win over the
        defaults chosen here, as do the user's ``TQDM_*`` environment variables.

    Returns
    -------
    tqdm
        A live bar, a notebook bar, or a :class:`LineTqdm`.
    """
    fp = sys.stderr if file is None else file
    if _in_notebook() and file is None:
        from tqdm.auto import tqdm as auto_tqdm

        cls: type[tqdm] = auto_tqdm
        defaults: dict[str, Any] = {}
    elif _tty(fp):
        cls, defaults = tqdm, {"mininterval": TTY_INTERVAL_S, "dynamic_ncols": True}
    else:
        cls, defaults = LineTqdm, {"mininterval": LINE_INTERVAL_S, "ascii": True}
    # tqdm reads TQDM_<OPTION> as a default that an explicit argument would hide
    defaults = {k: v for k, v in defaults.items() if f"TQDM_{k.upper()}" not in os.environ}
    return cls(total=total, desc=desc, unit=unit, file=fp, **{**defaults, **kwargs})


def start_clock(bar: tqdm | None) -> None:
    """Count the bar's rate, and so its remaining time, from now on.

    The units before (a sweep's first runs, which include the workers' start-up:
    compiling the kernels on first use, up to a minute) are left out of the rate.
    The elapsed time stays the true one, and the final line's overall rate
    includes everything.
    """
    if bar is None or getattr(bar, "disable", False):
        return
    from tqdm.std import EMA

    bar.smoothing = bar.smoothing or 0.3  # the average over all units would count start-up
    bar._ema_dn = EMA(bar.smoothing)
    bar._ema_dt = EMA(bar.smoothing)
    bar.last_print_n = bar.n
    bar.last_print_t = bar._time()


class WarmingBar:
    """A :func:`progress_bar` whose rate and remaining time start after its first ``warm``
    units.

    Until then it is drawn with :data:`WARMING_FORMAT` (no rate, no estimate) and
    ``note`` as its postfix; after them :func:`start_clock` restarts the rate, and
    the usual format returns once tqdm has measured a rate since. Everything else
    is the bar's (``set_postfix_str``, ``close``, ``n``...).

    Parameters
    ----------
    total : int
        Units the bar counts.
    warm : int
        Units that include start-up (e.g. one run per worker).
    note : str
        Postfix shown until the first ``warm`` units are done.
    make : callable, optional
        What makes the bar (default :func:`progress_bar`).
    **kwargs
        Further :func:`progress_bar` options.
    """

    def __init__(
        self, total: int, warm: int, note: str = "", make: Any = None, **kwargs: Any
    ) -> None:
        make = make or progress_bar
        self._bar = make(total=total, bar_format=WARMING_FORMAT, postfix=note or None,
                         **kwargs)  # fmt: skip
        self._warm = max(1, int(warm))
        self._done = 0
        self._clock = False
        self._note = note

    @property
    def total(self) -> float | None:
        return self._bar.total

    @total.setter
    def total(self, value: float | None) -> None:
        self._bar.total = value

    def update(self, n: int = 1) -> None:
        bar = self._bar
        bar.update(n)
        self._done += n
        if getattr(bar, "disable", False):
            return  # a disabled bar (TQDM_DISABLE) has no format or postfix to change
        if not self._clock and self._done >= self._warm:
            start_clock(bar)
            self._clock = True
            if self._note and str(bar.postfix or "") == self._note:
                bar.set_postfix_str("", refresh=False)  # started: the note no longer holds
        elif self._clock and bar.bar_format is not None and bar._ema_dt():
            bar.bar_format = None  # a rate measured after start-up: show it, and the estimate
            bar.refresh()

    def close(self) -> None:
        """Close the bar; its last line gives the overall rate, start-up included."""
        if not getattr(self._bar, "disable", False):
            self._bar.bar_format = None
        self._bar.close()

    def __getattr__(self, name: str) -> Any:
        return getattr(self._bar, name)


def finish(bar: tqdm | None) -> None:
    """Close ``bar`` at its real end: a total never reached becomes the count done.

    A workflow that stops before its planned budget ends its bar at ``n/n``, not
    at ``n/planned``. (An interrupted sweep keeps ``n/total``: it did stop short.)
    """
    if bar is None:
        return
    if bar.total is not None and bar.n < bar.total and not getattr(bar, "disable", False):
        bar.total = bar.n
        bar.refresh()
    bar.close()
