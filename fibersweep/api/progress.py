"""Progress of a sweep: the hooks a caller may give, the bar the CLI shows."""

from __future__ import annotations

import logging
from collections import Counter
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # annotations only: the API imports what it runs when it runs it
    from fibersweep.config import Config
    from fibersweep.config.flow import FlowSettings
    from fibersweep.sweep.plan import SweepPlan


log = logging.getLogger("fibersweep.api")


class SweepProgress:
    """What a sweep reports while it runs; :func:`run` calls these hooks in this order.

    The base class logs the plan and the rounds (logger ``fibersweep.api``, level
    INFO) and shows nothing. Subclass it to follow a sweep: :class:`SweepBar` shows a
    progress bar, the command line adds its printed lines to that.

    Attributes
    ----------
    bars : bool
        Also show a bar over the steps of a flow field that is computed.
    """

    bars = False

    def start(self, config: Config, fields: Mapping[str, tuple[FlowSettings, bool]]) -> None:
        """Before anything runs: the resolved config and its flow fields (key ->
        (settings, whether cached); :func:`fibersweep.sweep.fields.flow_keys_for`)."""
        missing = sum(1 for _, cached in fields.values() if not cached)
        log.info("%s: %d flow fields, %d to compute", config.run.output, len(fields), missing)

    def plan(self, plan: SweepPlan) -> None:
        """The plan of the sweep's first round, before it runs."""
        log.info(
            "%s: %d runs in the sweep; done %d ok, %d failed; to do now %d",
            plan.out, len(plan.tasks), plan.done_ok, plan.done_failed, len(plan.todo),
        )  # fmt: skip

    def row(self, row: Mapping[str, Any]) -> None:
        """A finished run: its row of the runs table."""

    def round(self, number: int, plan: SweepPlan) -> None:
        """Before refinement round ``number`` runs, with its plan."""
        log.info("refinement round %d: %d runs to do", number, len(plan.todo))

    def close(self) -> None:
        """The sweep is over (done, failed or interrupted)."""


class _Rows(SweepProgress):
    """Calls a function with each finished row."""

    def __init__(self, fn: Callable[[Mapping[str, Any]], None]) -> None:
        self._fn = fn

    def row(self, row: Mapping[str, Any]) -> None:
        self._fn(row)


#: Short names of the classes and modes in a sweep's bar.
SHORT = {"Below": "B", "Above": "A", "Pole-vaulting": "PV", "Trapping": "T", "failed": "fail",
         "zigzag": "Z", "displacement": "D", "wrap-and-jump": "WJ", "trapped": "T",
         "mixed": "M"}  # fmt: skip


class SweepBar(SweepProgress):
    """A progress bar over a sweep's runs, with the running count per class (or mode).

    On a terminal a live bar; into a log file a line every 10 s. The first run of
    each worker includes its start-up (kernels compiled on first use): the rate and
    the estimate start after them. One bar per refinement round.

    Attributes
    ----------
    counts : Counter
        Finished runs of this call per class (a pillar array's: per mode), failed
        runs as ``failed``.
    config : Config or None
        The sweep's resolved config (once started).
    """

    bars = True

    def __init__(self) -> None:
        self.counts: Counter = Counter()
        self.config: Config | None = None
        self._bar: Any = None

    @property
    def saved(self) -> int:
        """Runs of this call finished (and saved) so far."""
        return sum(self.counts.values())

    def start(self, config: Config, fields: Mapping[str, tuple[FlowSettings, bool]]) -> None:
        self.config = config

    def _new(self, n: int) -> None:
        from fibersweep.progressbar import WarmingBar

        workers = self.config.run.workers if self.config is not None else 1
        self._bar = WarmingBar(
            n,
            warm=min(workers, n),
            note="workers starting (the first runs also compile the kernels)",
            unit="run",
            smoothing=0.1,
        )

    def plan(self, plan: SweepPlan) -> None:
        if plan.todo:
            self._new(len(plan.todo))

    def row(self, row: Mapping[str, Any]) -> None:
        label = row.get("mode") or row["class"]  # a pillar array's runs: the mode
        self.counts[label if row["status"] == "ok" else "failed"] += 1
        bar = self._bar
        if bar is not None:
            counts = self.counts
            shown = [k for k in SHORT if counts[k]] + [k for k in counts if k not in SHORT]
            bar.set_postfix_str(
                " ".join(f"{SHORT.get(k, k or '?')}={counts[k]}" for k in shown), refresh=False
            )
            bar.update(1)

    def round(self, number: int, plan: SweepPlan) -> None:
        self.close()
        if plan.todo:
            self._new(len(plan.todo))

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None


def _progress(progress: bool | SweepProgress | Callable[..., Any] | None) -> SweepProgress:
    if isinstance(progress, SweepProgress):
        return progress
    if progress is True:
        return SweepBar()
    if callable(progress):
        return _Rows(progress)
    return SweepProgress()
