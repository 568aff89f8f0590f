"""Every benchmark under scripts/benchmarks declares a smoke pass.

CI runs ``scripts/benchmarks/run.py --smoke`` after the test suite; a benchmark without
``SMOKE`` stops that pass. Checked here so the fast suite names the script first.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

RUNNER = Path(__file__).resolve().parents[2] / "scripts" / "benchmarks" / "run.py"


def _runner():
    spec = importlib.util.spec_from_file_location("bench_runner", RUNNER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


RUN = _runner()


@pytest.mark.parametrize("name", sorted(RUN.benchmarks()))
def test_benchmark_declares_smoke(name):
    runs = RUN.smoke_args(RUN.benchmarks()[name])
    assert runs and all(isinstance(a, list) for a in runs)
    assert all(isinstance(x, str) for a in runs for x in a)


def test_a_script_without_smoke_is_named(tmp_path):
    script = tmp_path / "bench_nothing.py"
    script.write_text('"""No smoke."""\n', encoding="utf-8")
    with pytest.raises(SystemExit, match="bench_nothing.py declares no SMOKE"):
        RUN.smoke_args(script)
