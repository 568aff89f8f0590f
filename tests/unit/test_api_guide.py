"""The Python blocks of docs/python-api.md run, in order, as a notebook would run them.

``tests/docs/test_docs.py`` runs the docs' ```bash blocks; the guide to the Python
API is ```python blocks that build on each other, so they are run here: all of them,
in the page's order, as one script given to a fresh interpreter with ``-c`` (as in a
notebook, the main module has no file, which the sweep's spawned workers would run
again), in a scratch folder
that holds a copy of ``configs/`` and a ``.fibersweep-cache`` linked to the shared
test flow-field cache (the same folder ``test_docs.py`` gives a page). A block that
fails names its line in the page.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
GUIDE = REPO / "docs" / "python-api.md"
#: Seconds the whole page may take (about a minute on a quiet machine, cache warm).
TIMEOUT_S = 900
_FENCE = re.compile(r"^\s*```(\w*)\s*$")


def python_blocks(path: Path) -> list[tuple[int, str]]:
    """(first line, code) of every ```python block of ``path``, in order."""
    blocks, current, start, lang = [], None, 0, ""
    for no, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1):
        fence = _FENCE.match(line)
        if fence and current is None:
            current, start, lang = [], no + 1, fence.group(1)
        elif fence:
            if lang == "python":
                blocks.append((start, "\n".join(current)))
            current = None
        elif current is not None:
            current.append(line)
    assert current is None, f"{path.name}: a ``` block is not closed"
    return blocks


def test_the_blocks_are_read_in_order(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("a\n```python\nx = 1\n```\n```text\nno\n```\n```python\nprint(x)\n```\n")
    assert python_blocks(page) == [(3, "x = 1"), (9, "print(x)")]


def test_every_python_block_of_the_guide_runs(tmp_path, flow_cache_dir):
    blocks = python_blocks(GUIDE)
    assert len(blocks) >= 8, "the guide lost its blocks"
    work = tmp_path / "work"
    shutil.copytree(REPO / "configs", work / "configs")
    (work / ".fibersweep-cache").symlink_to(flow_cache_dir, target_is_directory=True)
    script, where = [], {}  # script line -> the page's line
    for start, code in blocks:
        script.append(f"print('--- block at docs/python-api.md:{start}', flush=True)")
        for k, line in enumerate(code.splitlines()):
            script.append(line)
            where[len(script)] = start + k
    env = {**os.environ, "MPLBACKEND": "Agg", "NO_COLOR": "1"}
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH")]))
    proc = subprocess.run(
        [sys.executable, "-c", "\n".join(script) + "\n"], cwd=work, env=env,
        capture_output=True, text=True, timeout=TIMEOUT_S,
    )  # fmt: skip
    if proc.returncode != 0:
        lines = [int(n) for n in re.findall(r'File "<string>", line (\d+)', proc.stderr)]
        at = f"docs/python-api.md:{where.get(lines[-1], '?')}" if lines else "docs/python-api.md"
        raise AssertionError(f"{at}: the block fails\n{(proc.stdout + proc.stderr)[-3000:]}")
    assert (work / "results" / "api" / "manifest.json").exists()
    assert (work / "api-figure.png").stat().st_size > 5000
    assert "separatrix y/h_obs" in proc.stdout and "Pole-vaulting" in proc.stdout
