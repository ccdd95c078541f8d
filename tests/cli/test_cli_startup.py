"""Start-up: ``scopelink --help`` and ``status --help`` load no command's machinery (docs/cli.md).

Each check runs ``python -X importtime -m scopelink ...`` as a user would and reads every module
the interpreter imported from its report; no timing is asserted (that is ``bench/startup.py``).
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
from pathlib import Path

import pytest

from scopelink.cli.commands import COMMANDS
from scopelink.cli.main import build_parser

HEAVY = ("aiohttp", "numpy", "erfa", "scopelink.web", "scopelink.servers")
"""What no help or version may import: the dashboard, the servers and the astronomy stack."""


def imported_by(tmp_path: Path, *args: str) -> set[str]:
    """Every module ``scopelink ARGS`` imports (its exit status must be 0)."""
    env = {**os.environ, "SCOPELINK_CONFIG": str(tmp_path / "absent.toml")}
    result = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "scopelink", *args],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
        env=env,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    lines = [line for line in result.stderr.splitlines() if line.startswith("import time:")]
    modules = {line.rsplit("|", 1)[1].strip() for line in lines[1:]}  # [0] is the header
    assert "scopelink.cli.main" in modules, result.stderr[-2000:]
    return modules


def loaded(modules: set[str], packages: tuple[str, ...]) -> list[str]:
    return sorted(m for m in modules if any(m == p or m.startswith(p + ".") for p in packages))


@pytest.mark.parametrize("args", [("--help",), ("--version",), ("status", "--help")])
def test_help_and_version_import_no_heavy_package(tmp_path: Path, args: tuple[str, ...]) -> None:
    modules = imported_by(tmp_path, *args)
    assert loaded(modules, HEAVY) == []


def test_help_imports_no_command_module(tmp_path: Path) -> None:
    modules = imported_by(tmp_path, "--help")
    command_modules = tuple(f"scopelink.cli.{c.module}" for c in COMMANDS)
    assert loaded(modules, command_modules) == []
    assert loaded(modules, ("scopelink.mount", "scopelink.astro", "scopelink.sim")) == []


def test_status_help_imports_only_the_status_command(tmp_path: Path) -> None:
    modules = imported_by(tmp_path, "status", "--help")
    others = tuple(f"scopelink.cli.{c.module}" for c in COMMANDS if c.name != "status")
    assert loaded(modules, others) == []
    assert loaded(modules, ("scopelink.mount", "scopelink.astro", "scopelink.sim")) == []


def test_status_runs_without_the_dashboard(tmp_path: Path) -> None:
    modules = imported_by(tmp_path, "status", "--json", "--device", "sim")
    assert "scopelink.cli.status_view" in modules  # it did run
    assert loaded(modules, ("scopelink.web", "aiohttp")) == []


def test_every_listed_command_is_filled_in_by_its_module() -> None:
    """A command listed under the wrong module (or not registered by it) stays a bare parser."""
    parser = build_parser()
    [action] = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    assert list(action.choices) == [command.name for command in COMMANDS]
    for command in COMMANDS:
        subparser = action.choices[command.name]
        subparser.format_help()
        assert subparser.description, command.name
        assert subparser.get_default("run") or command.name == "emulate", command.name
