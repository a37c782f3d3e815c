"""Shared fixtures of the Python module's tests: the repository, the CLI, a scratch folder."""
import os
import pathlib
import subprocess

import pytest

SOURCE = pathlib.Path(os.environ.get("HYBRIDTREE_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
CLI = os.environ.get("HYBRIDTREE_CLI", str(SOURCE / "build" / "bin" / "hybridtree"))


def run_cli(*args, check=True):
    """Runs the hybridtree CLI; returns the completed process (stdout and stderr as text)."""
    return subprocess.run([CLI, *map(str, args)], capture_output=True, text=True, check=check)


@pytest.fixture
def source():
    return SOURCE
