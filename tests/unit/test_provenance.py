"""The git revision recorded is fibersweep's own, never that of a user's repository."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from fibersweep.sweep.manifest import git_revision

pytestmark = pytest.mark.skipif(shutil.which("git") is None, reason="needs git")


def _repo(path, pyproject: str | None):
    path.mkdir(parents=True)
    env = ["-c", "user.name=t", "-c", "user.email=t@t"]
    subprocess.run(["git", "init", "-q", str(path)], check=True)
    (path / "README").write_text("x")
    if pyproject is not None:
        (path / "pyproject.toml").write_text(pyproject)
    subprocess.run(["git", "-C", str(path), "add", "-A"], check=True)
    subprocess.run(["git", *env, "-C", str(path), "commit", "-qm", "c"], check=True)


def test_an_installed_copy_inside_a_users_repository_records_no_revision(tmp_path):
    # a user's project with a virtual environment inside it: site-packages is in their tree
    user = tmp_path / "project"
    _repo(user, '[project]\nname = "my-analysis"\n')
    site = user / ".venv" / "lib" / "python3.11" / "site-packages"
    site.mkdir(parents=True)
    assert git_revision(site) is None  # not the user's HEAD
    assert git_revision(user) is None  # a repository, but not fibersweep's


def test_fibersweep_checkout_records_its_commit(tmp_path):
    repo = tmp_path / "fibersweep"
    _repo(repo, '[project]\nname = "fibersweep"\n')
    head = subprocess.run(
        ["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
    assert git_revision(repo) == head
    (repo / "README").write_text("changed")
    assert git_revision(repo) == head + "+dirty"


REPO = Path(__file__).resolve().parents[2]


@pytest.mark.slow  # a real pip build of the package (about 10 s, more on a loaded machine)
def test_a_non_editable_install_records_the_commit_it_was_built_from(tmp_path):
    """`pip install PATH` (not -e): no git checkout beside the installed package, so the
    revision must come from the build (setuptools-scm's fibersweep/_version.py)."""
    import os
    import sys

    if not (REPO / ".git").exists():
        pytest.skip("needs fibersweep's own git checkout to build from")
    target = tmp_path / "site"
    subprocess.run(
        [sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--target",
         str(target), str(REPO)],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    head = subprocess.run(
        ["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True, check=True
    ).stdout.strip()
    code = (
        "import json, fibersweep; from fibersweep.sweep.manifest import provenance;"
        "p = provenance('k'); print(json.dumps([fibersweep.__file__, p['git'], p['git_from'],"
        " p['fibersweep']]))"
    )
    env = {**os.environ, "PYTHONPATH": str(target)}
    out = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True,
        check=True,
    ).stdout  # fmt: skip
    where, rev, source, version = json.loads(out)
    assert where.startswith(str(target))  # the installed copy, not the checkout
    assert source == "build"
    assert rev and head.startswith(rev.removesuffix("+dirty")) and len(rev) >= 7
    assert rev.removesuffix("+dirty")[:7] in version  # the version is derived from git too
