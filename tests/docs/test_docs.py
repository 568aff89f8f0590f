"""Every command the documentation shows is run, so none goes stale.

Each ```bash block of README.md and docs/*.md is split into commands (one per
line; ``#`` comments allowed; a line ending in ``\\`` continues on the next).
The commands of one file run in order, in one scratch folder that holds a copy of
``configs/`` and a ``.fibersweep-cache`` linked to the shared test flow-field cache,
so a file can build on its own earlier commands (``run`` then ``plot-phase``).
``fibersweep`` is this checkout's command line (``python -m fibersweep`` with the
repository first on PYTHONPATH), whatever is installed.

Markers, written as a trailing comment on the command's line:

* ``# doc-test: slow``: takes more than about 30 s (at most ``SLOW_LINE_TIMEOUT_S``);
  run only in the slow suite (``pytest -m slow``), where every line of the file runs
  but the study lines;
* ``# doc-test: study <time>``: a study that takes longer than a slow line may (a full
  sweep at the source's resolution, a band-pass map), with its time; run only by
  ``pytest --studies -m study tests/docs``, where every line runs, without a limit;
* ``# doc-test: skip <why>``: never run here (an install, a cluster command);
* ``# doc-test: exit N``: the command must exit with code N (the point of the example).

One test per file, so a failure names the file and the line. Lines without a
marker must not depend on a slow line before them, nor slow lines on a study line.
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
#: Seconds one command may take before the test fails: a line without a marker, and a
#: ``slow`` one (a whole discrepancy analysis of 60 fibers takes 5-10 minutes on two free
#: cores, and longer on a shared machine).
LINE_TIMEOUT_S = 600
SLOW_LINE_TIMEOUT_S = 2400
_MARK = re.compile(r"#\s*doc-test:\s*(slow|study|skip|exit)\b\s*(.*)$")
_FENCE = re.compile(r"^\s*```(\w*)")


@dataclass(frozen=True)
class Command:
    """One command of a ```bash block.

    Attributes
    ----------
    file : str
        Path relative to the repository root.
    line : int
        1-based line of the command in the file.
    text : str
        The shell command (comments kept: bash ignores them).
    mode : str
        ``run``, ``slow``, ``study`` or ``skip``.
    exit_code : int
        Expected exit status.
    """

    file: str
    line: int
    text: str
    mode: str = "run"
    exit_code: int = 0


def doc_files() -> list[Path]:
    """README.md, CHANGELOG.md and every .md under docs/ (its folders too), in name order."""
    top = [p for p in (REPO / "README.md", REPO / "CHANGELOG.md") if p.exists()]
    return [*top, *sorted((REPO / "docs").rglob("*.md"))]


def extract(path: Path) -> list[Command]:
    """The commands of every ```bash block of ``path``, in order.

    Raises
    ------
    ValueError
        An unknown marker, an ``exit`` marker without a number, or an unclosed block.
    """
    rel = str(path.relative_to(REPO)) if REPO in path.resolve().parents else path.name
    out: list[Command] = []
    in_bash = in_block = False
    pending: list[str] = []
    start = 0
    lines = path.read_text(encoding="utf-8").splitlines()
    for no, raw in enumerate(lines, start=1):
        fence = _FENCE.match(raw)
        if fence:
            if pending:
                raise ValueError(f"{rel}:{start}: command continued with '\\' past its block")
            if in_block:
                in_block = in_bash = False
            else:
                in_block, in_bash = True, fence.group(1) == "bash"
            continue
        if not in_bash:
            continue
        stripped = raw.strip()
        if not pending and (not stripped or stripped.startswith("#")):
            continue
        if not pending:
            start = no
        if stripped.endswith("\\"):
            pending.append(stripped[:-1])
            continue
        text = " ".join([*pending, stripped])
        pending = []
        out.append(_command(rel, start, text))
    if in_block:
        raise ValueError(f"{rel}: a ``` block is not closed")
    return out


def _command(rel: str, line: int, text: str) -> Command:
    m = _MARK.search(text)
    if not m:
        if "doc-test" in text:
            raise ValueError(f"{rel}:{line}: unknown doc-test marker in {text!r}")
        return Command(rel, line, text)
    kind, arg = m.group(1), m.group(2).strip()
    if kind == "exit":
        if not re.fullmatch(r"\d+", arg.split(" ")[0] if arg else ""):
            raise ValueError(f"{rel}:{line}: '# doc-test: exit' needs a number")
        return Command(rel, line, text, exit_code=int(arg.split(" ")[0]))
    if kind in ("skip", "study") and not arg:
        why = "a reason" if kind == "skip" else "its time"
        raise ValueError(f"{rel}:{line}: '# doc-test: {kind}' needs {why}")
    return Command(rel, line, text, mode=kind)


def _scratch(tmp: Path, flow_cache: Path) -> tuple[Path, dict[str, str]]:
    """A folder with a copy of configs/ and the shared cache; env with our ``fibersweep``."""
    work = tmp / "work"
    shutil.copytree(REPO / "configs", work / "configs", symlinks=False)
    (work / ".fibersweep-cache").symlink_to(flow_cache, target_is_directory=True)
    bin_dir = tmp / "bin"
    bin_dir.mkdir()
    shim = bin_dir / "fibersweep"
    shim.write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} -m fibersweep "$@"\n')
    shim.chmod(0o755)
    # A wrapper, not a symlink: a symlink to a virtual environment's interpreter placed
    # in another folder starts the base interpreter, without the environment's packages.
    for name in ("python", "python3"):
        wrapper = bin_dir / name
        wrapper.write_text(f'#!/bin/sh\nexec {shlex.quote(sys.executable)} "$@"\n')
        wrapper.chmod(0o755)
    env = dict(os.environ)
    env["PATH"] = f"{bin_dir}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(REPO), env.get("PYTHONPATH")]))
    env["FIBERSWEEP_REPO"] = str(REPO)
    env.pop("FORCE_COLOR", None)
    env["NO_COLOR"] = "1"
    return work, env


#: The lines each tier runs: the default suite, ``-m slow``, ``--studies -m study``.
TIERS = {"run": ("run",), "slow": ("run", "slow"), "study": ("run", "slow", "study")}
#: Seconds a line of each mode may take (a study line has no limit).
LIMITS = {"run": LINE_TIMEOUT_S, "slow": SLOW_LINE_TIMEOUT_S}


def _run_file(rel: str, commands: list[Command], tmp: Path, flow_cache: Path, tier: str):
    work, env = _scratch(tmp, flow_cache)
    ran = 0
    for cmd in commands:
        if cmd.mode not in TIERS[tier]:
            continue
        # the scripts of the repository are reachable as in a checkout
        if "scripts/" in cmd.text and not (work / "scripts").exists():
            (work / "scripts").symlink_to(REPO / "scripts", target_is_directory=True)
        limit = LIMITS.get(cmd.mode)
        try:
            proc = subprocess.run(
                ["bash", "-o", "pipefail", "-c", cmd.text],
                cwd=work, env=env, capture_output=True, text=True, timeout=limit,
            )  # fmt: skip
        except subprocess.TimeoutExpired:
            pytest.fail(f"{cmd.file}:{cmd.line}: timed out after {limit} s: {cmd.text}")
        ran += 1
        if proc.returncode != cmd.exit_code:
            tail = (proc.stdout + proc.stderr)[-3000:]
            pytest.fail(
                f"{cmd.file}:{cmd.line}: exit {proc.returncode} (expected {cmd.exit_code}): "
                f"{cmd.text}\n--- output (tail) ---\n{tail}",
                pytrace=False,
            )
    return ran


_FILES = [p for p in doc_files() if p.exists()]
_IDS = [str(p.relative_to(REPO)) for p in _FILES]


@pytest.mark.parametrize("path", _FILES, ids=_IDS)
def test_doc_commands(path: Path, tmp_path: Path, flow_cache_dir: Path) -> None:
    """The file's commands without a slow or skip marker all exit as documented."""
    cmds = extract(path)
    if not any(c.mode == "run" for c in cmds):
        pytest.skip("no command to run outside the slow suite")
    _run_file(str(path), cmds, tmp_path, flow_cache_dir, tier="run")


@pytest.mark.slow
@pytest.mark.parametrize("path", _FILES, ids=_IDS)
def test_doc_commands_slow(path: Path, tmp_path: Path, flow_cache_dir: Path) -> None:
    """Every command of the file, slow ones included, in order (not the studies)."""
    cmds = extract(path)
    if not any(c.mode == "slow" for c in cmds):
        pytest.skip("no slow command")
    _run_file(str(path), cmds, tmp_path, flow_cache_dir, tier="slow")


@pytest.mark.study
@pytest.mark.parametrize("path", _FILES, ids=_IDS)
def test_doc_commands_study(path: Path, tmp_path: Path, flow_cache_dir: Path) -> None:
    """Every command of the file, studies included, in order (hours; collected only with
    ``--studies``, tests/conftest.py)."""
    cmds = extract(path)
    if not any(c.mode == "study" for c in cmds):
        pytest.skip("no study command")
    _run_file(str(path), cmds, tmp_path, flow_cache_dir, tier="study")


def test_readme_set_up_commands_are_what_ci_runs() -> None:
    """The README's two set-up commands (install and run, install and test) are the ones
    .ci/run executes, inside the virtual environment it creates."""
    readme = [c.text for c in extract(REPO / "README.md")]
    ci = (REPO / ".ci" / "run").read_text(encoding="utf-8")
    setup = [c for c in readme if "pip install -e" in c]
    assert len(setup) == 2 and any("pytest" in c for c in setup), setup
    venv = ci.index("venv/bin/activate")
    for cmd in setup:
        line = cmd.split("#")[0].strip()
        assert line in ci, f"README set-up command {line!r} is not in .ci/run"
        assert ci.index(line) > venv, f"{line!r} runs before .ci/run activates its venv"


def test_extract_markers(tmp_path: Path) -> None:
    """Blocks, continuation lines and markers are read as the convention says."""
    doc = tmp_path / "selftest.md"
    text = (
        "text\n```bash\n# a comment\nfibersweep --version\n"
        "fibersweep run a.yaml \\\n  --dry-run   # doc-test: slow\n"
        "fibersweep run bad.yaml  # doc-test: exit 2\n"
        "sbatch x.sh  # doc-test: skip cluster only\n"
        "fibersweep run paper.yaml  # doc-test: study 3 hours\n```\n"
        "```text\nnot a command\n```\n```yaml\nflow: {}\n```\n"
    )
    doc.write_text(text, encoding="utf-8")
    cmds = extract(doc)
    assert [(c.line, c.mode, c.exit_code) for c in cmds] == [
        (4, "run", 0), (5, "slow", 0), (7, "run", 2), (8, "skip", 0), (9, "study", 0),
    ]  # fmt: skip
    assert " ".join(cmds[1].text.split()).startswith("fibersweep run a.yaml --dry-run #")
    with pytest.raises(ValueError, match="needs a reason"):
        _command("x.md", 1, "sbatch x.sh  # doc-test: skip")
    with pytest.raises(ValueError, match="needs its time"):
        _command("x.md", 1, "fibersweep run paper.yaml  # doc-test: study")
    with pytest.raises(ValueError, match="unknown doc-test marker"):
        _command("x.md", 1, "ls  # doc-test: sloww")


def test_every_doc_figure_exists_and_is_small() -> None:
    """Images linked from the docs exist in the repository and are under 300 KB."""
    for path in _FILES:
        text = path.read_text(encoding="utf-8")
        for target in re.findall(r"!\[[^\]]*\]\(([^)\s]+)\)", text):
            img = (path.parent / target).resolve()
            assert img.is_file(), f"{path.name}: missing figure {target}"
            assert REPO in img.parents, f"{path.name}: figure outside the repository: {target}"
            assert img.stat().st_size < 300_000, f"{target}: {img.stat().st_size} B"


def test_no_reference_outside_the_repository() -> None:
    """Docs link only to files of the repository (no ../shared, no absolute paths)."""
    for path in _FILES:
        text = path.read_text(encoding="utf-8")
        assert "SPEC.md" not in text, f"{path.name} points to SPEC.md"
        for target in re.findall(r"\]\(([^)\s#]+)", text):
            if re.match(r"[a-z]+://", target):
                continue
            resolved = (path.parent / target).resolve()
            assert REPO in resolved.parents or resolved == REPO, f"{path.name}: {target}"
            assert resolved.exists(), f"{path.name}: broken link {target}"


def _slug(heading: str) -> str:
    """The anchor GitHub gives a Markdown heading."""
    text = re.sub(r"[^\w\- ]", "", heading.strip().lower())
    return text.replace(" ", "-")


def anchors(path: Path) -> set[str]:
    """Every heading anchor of a Markdown file (a repeated heading gets -1, -2, ...)."""
    seen: dict[str, int] = {}
    out = set()
    in_code = False
    for line in path.read_text(encoding="utf-8").splitlines():
        if _FENCE.match(line):
            in_code = not in_code
        m = re.match(r"(#{1,6}) (.+)", line)
        if m and not in_code:
            slug = _slug(m.group(2))
            n = seen.get(slug, 0)
            seen[slug] = n + 1
            out.add(slug if n == 0 else f"{slug}-{n}")
    return out


def test_every_link_and_anchor_resolves() -> None:
    """Every relative link of README and docs names a file, and its #anchor a heading there."""
    bad = []
    for path in _FILES:
        text = re.sub(r"```.*?```", "", path.read_text(encoding="utf-8"), flags=re.S)
        for target in re.findall(r"\]\(([^)\s]+)\)", text):
            if re.match(r"[a-z]+:", target):
                continue
            file, _, anchor = target.partition("#")
            dest = (path.parent / file).resolve() if file else path
            rel = path.relative_to(REPO)
            if not dest.exists():
                bad.append(f"{rel}: {target} (no such file)")
            elif anchor and dest.suffix == ".md" and anchor not in anchors(dest):
                bad.append(f"{rel}: {target} (no heading #{anchor} in {dest.name})")
    assert not bad, "\n".join(bad)


def test_slug_follows_github() -> None:
    assert _slug("Speed (`python3 scripts/benchmarks/bench_flexible.py`)") == (
        "speed-python3-scriptsbenchmarksbench_flexiblepy"
    )
    assert _slug("`fiber.effects`: the effects") == "fibereffects-the-effects"
    assert _slug("Reading the interval's ends") == "reading-the-intervals-ends"


def test_python_on_the_doc_path_is_the_tests_environment(tmp_path: Path) -> None:
    """``python3`` in a doc command sees the environment the tests run in (a venv too)."""
    _, env = _scratch(tmp_path, tmp_path)
    for name in ("python", "python3"):
        out = subprocess.run(
            [name, "-c", "import sys; print(sys.prefix)"],
            env=env, capture_output=True, text=True, check=True,
        )  # fmt: skip
        assert out.stdout.strip() == sys.prefix, f"{name} runs {out.stdout.strip()}"


def test_guide_pages_stay_short_and_undated() -> None:
    """A guide page (docs/*.md) says how the tool works today in under 400 lines, and no
    page has a dated section: history goes to git and CHANGELOG.md."""
    for path in sorted((REPO / "docs").glob("*.md")):
        n = len(path.read_text(encoding="utf-8").splitlines())
        assert n <= 400, f"{path.name}: {n} lines; move studies to docs/validation/"
    for path in _FILES:
        for line in path.read_text(encoding="utf-8").splitlines():
            if line.startswith("#") and path.name != "CHANGELOG.md":
                assert not re.search(r"\b20\d\d-\d\d-\d\d\b|[Vv]ersion\b", line), (
                    f"{path.relative_to(REPO)}: dated or version heading {line!r}"
                )


def test_the_module_map_names_every_module() -> None:
    """docs/architecture.md's module map lists every module of each package in its row,
    and names no module that does not exist (the effects' row says "one module per
    effect"; the version file is generated)."""
    rows: dict[str, set[str]] = {}
    for line in (REPO / "docs" / "architecture.md").read_text(encoding="utf-8").splitlines():
        m = re.match(r"\| `([a-z_/]+)` \| (.*?) \|", line)
        if m:
            rows[m.group(1).rstrip("/")] = set(re.findall(r"`([a-z_0-9]+)`", m.group(2)))
    package = REPO / "fibersweep"
    missing = []
    found: dict[str, set[str]] = {}
    for path in sorted(package.rglob("*.py")):
        rel = path.relative_to(package)
        where = "fibersweep" if rel.parent == Path(".") else rel.parent.as_posix()
        if path.stem in ("__init__", "__main__", "_version") or where == "fiber/effects":
            continue
        found.setdefault(where, set()).add(path.stem)
        if path.stem not in rows.get(where, set()):
            missing.append(f"{where}/{path.stem}")
    assert not missing, f"docs/architecture.md's module map leaves out {missing}"
    stale = [
        f"{where}/{name}"
        for where, names in rows.items()
        if where != "fiber/effects" and (where in found or (package / where).is_dir())
        for name in sorted(names - found.get(where, set()))
    ]
    assert not stale, f"docs/architecture.md's module map names modules that do not exist: {stale}"
