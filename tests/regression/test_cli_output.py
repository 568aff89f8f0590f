"""What a user sees: `fibersweep run` captured in a pseudo-terminal and in a file.

A fresh tmp cache makes the run compute its (small, 0.1 M cell) flow field, so both the
flow solver's bar and the sweep's bar appear. On a terminal the flow bar must be closed
(its line ended) before the sweep prints its plan, never be drawn again afterwards, and no
bar may sit on a second row (cursor-up escapes); into a file there must be no carriage
return or escape at all, only plain lines.
"""

from __future__ import annotations

import fcntl
import os
import pty
import select
import struct
import subprocess
import sys
import termios
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

CONFIG = """
flow:
  dx: 4.0
  geometry: {{width: 400.0, depth: 40.0, length: 800.0, pillar_height: 75.0}}
fiber:
  record: {{samples: 20}}
sweep:
  theta0: [0.0]
  y0: [0.2, 0.9]
  length: [1.0]
run:
  workers: 1
  output: {out}
  cache_dir: {cache}
"""


def _config(tmp: Path) -> Path:
    p = tmp / "tiny.yaml"
    p.write_text(CONFIG.format(out=tmp / "res", cache=tmp / "cache"))
    return p


def _env() -> dict[str, str]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("TQDM_")}
    env["PYTHONPATH"] = str(REPO) + os.pathsep + env.get("PYTHONPATH", "")
    return env


def _run_in_pty(args: list[str], cols: int = 100) -> tuple[int, str]:
    """Run with stdin, stdout and stderr on a pseudo-terminal; everything it drew."""
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 30, cols, 0, 0))
    proc = subprocess.Popen(
        args, stdin=slave, stdout=slave, stderr=slave, cwd=REPO, env=_env(), close_fds=True
    )
    os.close(slave)
    out = b""
    while True:
        ready, _, _ = select.select([master], [], [], 0.5)
        if ready:
            try:
                chunk = os.read(master, 65536)
            except OSError:  # EIO: the child closed the terminal
                break
            if not chunk:
                break
            out += chunk
        elif proc.poll() is not None:
            break
    os.close(master)
    return proc.wait(), out.decode("utf-8", "replace")


def test_run_on_a_terminal_closes_the_flow_bar_before_the_sweep(tmp_path):
    rc, text = _run_in_pty([sys.executable, "-m", "fibersweep", "run", str(_config(tmp_path))])
    assert rc == 0, text
    assert "flow field, dx = 4 µm" in text  # the flow bar was shown
    plan = text.index("runs in the sweep")
    line_start = text.rfind("\n", 0, plan)
    # the plan line starts on a fresh line: nothing of the flow bar glued before it
    assert text[line_start + 1 : plan].startswith(str(tmp_path / "res")), text[:plan]
    # the line before it is the flow bar's last draw (closed: its line was ended)
    last_draw = text[:line_start].rstrip("\r").split("\r")[-1]
    assert last_draw.startswith("flow field, dx = 4 µm") and "residual" in last_draw
    assert "\x1b[A" not in text  # no bar on a second row, no cursor-up
    after = text[text.index("table:") :]
    assert "flow field, dx" not in after and "%|" not in after  # nothing redrawn at the end
    assert "2/2" in text[plan:]  # the sweep bar reached its total
    summary = [ln for ln in text.split("\n") if "ran 2 runs" in ln]
    assert summary and summary[0].strip("\r").startswith("ran 2 runs"), summary


def test_run_into_a_file_writes_plain_lines(tmp_path):
    log = tmp_path / "run.log"
    with log.open("w") as fh:
        proc = subprocess.run(
            [sys.executable, "-m", "fibersweep", "run", str(_config(tmp_path))],
            stdout=fh, stderr=subprocess.STDOUT, cwd=REPO, env=_env(), check=False,
        )  # fmt: skip
    text = log.read_text()
    assert proc.returncode == 0, text
    assert "\r" not in text and "\x1b" not in text, repr(text)
    lines = text.splitlines()
    flow = [ln for ln in lines if ln.startswith("flow field, dx = 4 µm")]
    assert flow and "residual" in flow[-1]  # the flow bar's final state, on its own line
    assert "starting (the first solve also compiles the kernels)" in flow[0]
    runs = [ln for ln in lines if "run/s" in ln or "s/run" in ln]
    assert runs and "2/2" in runs[-1]
    # order: flow bar, then the plan, the sweep bar, the summary
    idx = [lines.index(flow[-1]), next(i for i, ln in enumerate(lines) if "in the sweep" in ln)]
    idx += [lines.index(runs[-1]), next(i for i, ln in enumerate(lines) if ln.startswith("table:"))]
    assert idx == sorted(idx), lines


def test_line_mode_is_what_a_cluster_job_gets(tmp_path):
    """A batch job's stderr is a file: the same path as above (no TTY, no kernel)."""
    code = (
        "import sys; from fibersweep.progressbar import progress_bar, LineTqdm;"
        "b = progress_bar(total=3); print(type(b).__name__); b.close()"
    )
    with (tmp_path / "err").open("w") as err:
        out = subprocess.run(
            [sys.executable, "-c", code], stderr=err, capture_output=False, env=_env(),
            stdout=subprocess.PIPE, text=True, cwd=REPO, check=True,
        ).stdout  # fmt: skip
    assert out.strip() == "LineTqdm"
