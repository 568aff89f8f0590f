"""Run the benchmarks of this folder: list them, run any or all, or a smoke pass of each.

Every ``bench_*.py`` and ``profile_*.py`` beside this file is a benchmark. Each measures
what it compares in one run (old against new, one setting against another, on the
same machine and load) and prints the ratios itself; this runner starts each in its
own process from the repository's root, shows its output and ends with a table of
exit codes and times.

``--smoke`` runs each benchmark with its ``SMOKE`` arguments, a module-level list in
the script (or a list of such lists, run in order) that makes it finish in seconds to a
minute: the script still runs end to end, so a change that breaks it fails here. The
numbers of a smoke run mean nothing. ``{tmp}`` in an argument is a fresh temporary
folder (one per benchmark, shared by its runs) and ``{cache}`` the tests' flow-field
cache (``FIBERSWEEP_TEST_CACHE``, else ``.fibersweep-cache/tests``), so a smoke pass
after the tests solves no field again.
Arguments after ``--`` go to every benchmark run by name or ``--all``.

    python3 scripts/benchmarks/run.py --list
    python3 scripts/benchmarks/run.py fiber lbm            # bench_fiber.py, bench_lbm.py
    python3 scripts/benchmarks/run.py fiber -- --repeat 5
    python3 scripts/benchmarks/run.py --all
    python3 scripts/benchmarks/run.py --smoke [NAME...]
"""

from __future__ import annotations

import argparse
import ast
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[1]


def benchmarks() -> dict[str, Path]:
    """Short name (``fiber`` for bench_fiber.py, ``profile_flexible``) -> script."""
    found = sorted([*HERE.glob("bench_*.py"), *HERE.glob("profile_*.py")])
    return {p.stem.removeprefix("bench_"): p for p in found}


def _module(path: Path) -> ast.Module:
    return ast.parse(path.read_text(encoding="utf-8"), filename=str(path))


def summary(path: Path) -> str:
    """First line of the script's docstring."""
    doc = ast.get_docstring(_module(path)) or ""
    return doc.strip().splitlines()[0] if doc.strip() else ""


def smoke_args(path: Path) -> list[list[str]]:
    """The script's ``SMOKE`` arguments as a list of argument lists.

    Raises
    ------
    SystemExit
        The script declares no ``SMOKE`` (every benchmark must have a smoke pass).
    """
    for node in _module(path).body:
        if isinstance(node, ast.Assign) and any(
            isinstance(t, ast.Name) and t.id == "SMOKE" for t in node.targets
        ):
            value = ast.literal_eval(node.value)
            if all(isinstance(a, str) for a in value):
                return [list(value)]
            return [list(a) for a in value]
    raise SystemExit(f"{path.name} declares no SMOKE: add the arguments of a run of seconds")


def run_one(path: Path, argv: list[str], timeout: float | None) -> tuple[int, float]:
    """Run ``path argv`` from the repository root, output passed through; (exit code, s)."""
    print(f"\n=== {path.relative_to(REPO)} {' '.join(argv)}", flush=True)
    t0 = time.perf_counter()
    try:
        code = subprocess.run(
            [sys.executable, str(path), *argv], cwd=REPO, timeout=timeout
        ).returncode
    except subprocess.TimeoutExpired:
        print(f"timed out after {timeout:.0f} s", flush=True)
        code = 124
    return code, time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    extra: list[str] = []
    if "--" in argv:
        extra, argv = argv[argv.index("--") + 1 :], argv[: argv.index("--")]
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("names", nargs="*", help="benchmarks to run (see --list)")
    ap.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    ap.add_argument("--all", action="store_true", help="run every benchmark in full")
    ap.add_argument("--smoke", action="store_true", help="run each (or NAMEs) with SMOKE")
    ap.add_argument("--timeout", type=float, default=None, help="seconds per run")
    args = ap.parse_args(argv)
    known = benchmarks()
    if args.list:
        width = max(map(len, known))
        for name, path in known.items():
            print(f"{name:<{width}}  {summary(path)}")
        return 0
    unknown = [n for n in args.names if n not in known]
    if unknown:
        ap.error(f"unknown benchmark(s) {', '.join(unknown)}; valid: {', '.join(known)}")
    names = args.names or (list(known) if args.all or args.smoke else [])
    if not names:
        ap.error("name benchmarks, or give --all, --smoke or --list")
    results = []
    cache = os.environ.get("FIBERSWEEP_TEST_CACHE", str(REPO / ".fibersweep-cache" / "tests"))
    with tempfile.TemporaryDirectory(prefix="bench-") as tmp:
        for name in names:
            path = known[name]
            runs = smoke_args(path) if args.smoke else [extra]
            folder = Path(tmp) / name  # one folder per benchmark, shared by its runs
            folder.mkdir()
            for run_argv in runs:
                run_argv = [a.replace("{tmp}", str(folder)).replace("{cache}", cache)
                            for a in run_argv]  # fmt: skip
                code, secs = run_one(path, run_argv, args.timeout)
                results.append((name, code, secs))
                if code != 0:
                    break
    print("\n| benchmark | exit | time [s] |\n|---|---|---|")
    for name, code, secs in results:
        print(f"| {name} | {code} | {secs:.1f} |")
    failed = [name for name, code, _ in results if code != 0]
    if failed:
        print(f"failed: {', '.join(failed)}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
