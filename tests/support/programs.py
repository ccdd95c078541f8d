"""Third-party programs the tests run (socat, INDI drivers, Chromium, wrk)."""

from __future__ import annotations

import shutil

import pytest


def require_executable(name: str) -> str:
    """The path of program ``name``; the test skips when missing (fails in CI: conftest.py)."""
    path = shutil.which(name)
    if path is None:
        pytest.skip(f"{name} is not installed (bash scripts/test.sh installs it)")
    return path
