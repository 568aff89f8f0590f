"""With -v, log lines go through tqdm, so they are never glued to a progress bar."""

from __future__ import annotations

import logging

from tqdm import tqdm

from fibersweep.cli._app import _setup_logging, _TqdmLogHandler


def test_log_lines_are_written_on_their_own_line_while_a_bar_runs(capsys):
    root = logging.getLogger()
    level = root.level
    try:
        _setup_logging(verbose=True)
        _setup_logging(verbose=True)  # a second command in one process: still one handler
        assert sum(isinstance(h, _TqdmLogHandler) for h in root.handlers) == 1
        bar = tqdm(total=10, desc="runs", mininterval=0)
        bar.update(3)
        logging.getLogger("fibersweep.test").info("worker started")
        bar.update(3)
        bar.close()
        err = capsys.readouterr().err
        lines = err.replace("\r", "\n").splitlines()
        logged = [ln for ln in lines if "worker started" in ln]
        assert logged and all(ln.split(" ")[0][:2] == "20" for ln in logged), (
            lines
        )  # starts with the date
        assert not any("runs" in ln for ln in logged)  # no bar text on the log line
    finally:
        for h in [h for h in root.handlers if isinstance(h, _TqdmLogHandler)]:
            root.removeHandler(h)
        root.setLevel(level)
