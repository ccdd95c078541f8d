"""scopelink's wheel, built once per test process (hatchling, as ``pip install .`` builds it) and
shared by every test that installs or unpacks it."""

from __future__ import annotations

import atexit
import functools
import shutil
import tempfile
from pathlib import Path

from hatchling.builders.wheel import WheelBuilder

ROOT = Path(__file__).resolve().parents[2]


@functools.cache
def scopelink_wheel() -> Path:
    """The path of the built wheel (removed when the test process ends)."""
    directory = Path(tempfile.mkdtemp(prefix="scopelink-wheel-"))
    atexit.register(shutil.rmtree, directory, ignore_errors=True)
    built = WheelBuilder(str(ROOT)).build(directory=str(directory), versions=["standard"])
    return Path(next(iter(built)))
