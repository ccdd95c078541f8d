"""A fresh project that installs scopelink's wheel and writes ten lines of test talks to each
emulator through the plugin's fixtures, with pyserial only (issue #18)."""

from __future__ import annotations

import subprocess
import sys
import sysconfig
import venv
from pathlib import Path

from tests.support.wheel import scopelink_wheel

TEN_LINES = r"""import serial
def ask(emulator, *exchanges):
    with serial.serial_for_url(emulator.serial_url, timeout=2) as port:
        return [port.write(command) and port.read(size) for command, size in exchanges]
def test_synscan(synscan_emulator): assert ask(synscan_emulator, (b"e", 18))[0][-1:] == b"#"
def test_tracker(skytracker_emulator):
    a, radec, _, version = ask(skytracker_emulator, (b"Q", 1), (b"\r", 16), (b"q", 0), (b"V", 8))
    assert (a, radec[-1:], version) == (b"A", b"\0", b"v4.0    ")
def test_commander(skycommander_emulator):
    assert ask(skycommander_emulator, (b"\r", 16))[0][-1:] == b"\0"
"""

NOT_FRESH = ("-p", "no:hypothesispytest", "-p", "no:asyncio", "-W", "ignore")
"""This venv's other pytest plugins, which a fresh project would not have (and which take most of
the start-up): the ``scopelink`` plugin is still found by its entry point."""


def test_a_fresh_project_pip_installs_the_wheel_and_its_ten_line_test_passes(
    tmp_path: Path,
) -> None:
    fresh = tmp_path / "venv"
    venv.create(fresh, with_pip=False)
    python = fresh / "bin" / "python"
    site_packages = Path(
        subprocess.run(
            [python, "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
            capture_output=True,
            text=True,
            check=True,
        ).stdout.strip()
    )
    # pytest and pyserial (and numpy...) come from this venv, read-only: no network, no builds
    (site_packages / "zz_test_venv.pth").write_text(sysconfig.get_paths()["purelib"] + "\n")
    install = [sys.executable, "-m", "pip", "install", "-q", "--disable-pip-version-check"]
    install += ["--no-compile"]  # the fresh interpreter compiles what it imports
    wheel = str(scopelink_wheel())
    subprocess.run(
        [*install, "--no-deps", "--no-index", "--target", site_packages, wheel], check=True
    )
    project = tmp_path / "project"
    project.mkdir()
    (project / "test_with_scopelink.py").write_text(TEN_LINES)
    assert len(TEN_LINES.splitlines()) == 10
    result = subprocess.run(
        [python, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--trace-config", *NOT_FRESH],
        cwd=project,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "3 passed" in result.stdout
    # the plugin came from the installed wheel, not from this checkout
    assert f"'scopelink.testing.plugin' from '{site_packages}" in result.stdout
