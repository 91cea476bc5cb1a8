"""Provenance: the git state recorded in manifests and run records."""

import os
import subprocess

from cadsim.provenance import git_state, package_versions


def _git(repo, *args):
    subprocess.run(["git", "-C", str(repo), *args], check=True, capture_output=True)


def test_dirty_counts_untracked_sources_but_not_reproduce_outputs(tmp_path):
    _git(tmp_path, "init", "-q")
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "table1.md").write_text("old\n")
    (tmp_path / "a.py").write_text("x = 1\n")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "init")
    state = git_state(tmp_path)
    assert len(state["commit"]) == 40 and state["dirty"] is False
    (tmp_path / "results" / "table1.md").write_text("new\n")  # written by make reproduce
    assert git_state(tmp_path)["dirty"] is False
    (tmp_path / "b.py").write_text("y = 2\n")  # an untracked source shapes results too
    assert git_state(tmp_path)["dirty"] is True


def test_no_checkout_gives_none(tmp_path):
    assert git_state(tmp_path / "nowhere") == {"commit": None, "dirty": None}


def test_package_versions_name_missing_packages_as_none():
    versions = package_versions(["numpy", "surely-not-a-package-cadsim"])
    assert (
        versions["numpy"] and versions["python"] and versions["surely-not-a-package-cadsim"] is None
    )


def test_git_state_leaves_the_checkout_untouched(tmp_path):
    """Issue 15 #7: a plain `git status` refreshes (rewrites) the index of a checkout whose files
    were touched, taking .git/index.lock; git_state must not."""
    _git(tmp_path, "init", "-q")
    (tmp_path / "a.py").write_text("x = 1\n")
    _git(tmp_path, "add", ".")
    _git(tmp_path, "-c", "user.name=t", "-c", "user.email=t@t", "commit", "-qm", "init")
    os.utime(tmp_path / "a.py", (978307200, 978307200))  # same content, new stat data
    index = tmp_path / ".git" / "index"
    before = (index.read_bytes(), index.stat().st_mtime_ns)
    listing = sorted(p.name for p in (tmp_path / ".git").iterdir())
    assert git_state(tmp_path)["dirty"] is False
    assert (index.read_bytes(), index.stat().st_mtime_ns) == before
    assert sorted(p.name for p in (tmp_path / ".git").iterdir()) == listing
