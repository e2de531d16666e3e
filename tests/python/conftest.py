"""Shared fixtures: the CLI binary and source tree ctest passes in (tests/python/CMakeLists.txt)."""
import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("ACTIONSHIFT_CLI")
    if not path or not os.path.exists(path):
        pytest.fail("ACTIONSHIFT_CLI is not set to the actionshift binary (run these tests through ctest)")

    def run(*args, stdin=None, check=None):
        p = subprocess.run([path, *args], input=stdin, capture_output=True, text=True, timeout=600)
        if check is not None:
            assert p.returncode == check, f"actionshift {' '.join(args)}: exit {p.returncode}\n{p.stderr}"
        return p

    return run


@pytest.fixture(scope="session")
def source_dir():
    return os.environ.get("ACTIONSHIFT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
