"""Shared fixtures: the repository root and the `pyrograph` CLI the tests compare against."""

import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """The CLI binary: $PYROGRAPH_BIN, else target/debug/pyrograph (built here if missing)."""
    path = os.environ.get("PYROGRAPH_BIN")
    if path:
        return pathlib.Path(path)
    path = ROOT / "target" / "debug" / "pyrograph"
    if not path.exists():
        subprocess.run(["cargo", "build", "-q", "--bin", "pyrograph"], cwd=ROOT, check=True)
    return path
