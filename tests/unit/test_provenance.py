"""The git revision recorded is fibersweep's own, never that of a user's repository."""

from __future__ import annotations

import shutil
import subprocess

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
