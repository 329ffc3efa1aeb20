"""The GitHub Actions workflows of .github/workflows pass actionlint (installed into the test
environment by .ci/bootstrap; it also runs shellcheck on the ``run:`` scripts when shellcheck
is on PATH)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
WORKFLOWS = sorted((REPO / ".github" / "workflows").glob("*.y*ml"))


def actionlint():
    """The actionlint binary: the test environment's (beside its python), else PATH's."""
    beside = Path(sys.executable).parent / ("actionlint.exe" if os.name == "nt" else "actionlint")
    return str(beside) if beside.is_file() else shutil.which("actionlint")


def test_there_are_workflows():
    assert any(p.name == "release.yml" for p in WORKFLOWS), WORKFLOWS


@pytest.mark.parametrize("workflow", WORKFLOWS, ids=lambda p: p.name)
def test_workflow_passes_actionlint(workflow):
    binary = actionlint()
    if binary is None:
        pytest.skip("actionlint is not installed (bash .ci/bootstrap installs it into .venv)")
    run = subprocess.run([binary, "-no-color", str(workflow.relative_to(REPO))], cwd=REPO,
                         capture_output=True, text=True, timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode == 0 and not run.stdout.strip(), \
        f"actionlint {workflow.name} (exit {run.returncode}):\n{run.stdout}{run.stderr}"


def test_actionlint_finds_a_broken_workflow(tmp_path):
    """The check above can fail: an undefined matrix key and an unknown job key are errors."""
    binary = actionlint()
    if binary is None:
        pytest.skip("actionlint is not installed (bash .ci/bootstrap installs it into .venv)")
    broken = tmp_path / "broken.yml"
    broken.write_text("on: push\njobs:\n  a:\n    runs-on: ${{ matrix.os }}\n    stepz: []\n")
    run = subprocess.run([binary, "-no-color", str(broken)], capture_output=True, text=True,
                         timeout=120, stdin=subprocess.DEVNULL)
    assert run.returncode != 0 and "broken.yml" in run.stdout, run.stdout + run.stderr
