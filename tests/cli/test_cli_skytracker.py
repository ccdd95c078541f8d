"""The device commands against the Sky Tracker emulator (with its Sky Commander), over TCP."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.cli import emulator, scopelink


@pytest.fixture(scope="module")
def device(tmp_path_factory: pytest.TempPathFactory) -> Iterator[str]:
    data = tmp_path_factory.mktemp("skytracker-data")
    with emulator("skytracker", "--no-pacing", "--data-dir", str(data)) as spec:
        yield spec


def test_info_reports_the_version_and_the_sky_commander(config: Path, device: str) -> None:
    result = scopelink(config, "info", device, "--json")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["protocol"] == "skytracker"
    assert report["model"] == "Sky Tracker + Sky Commander"
    assert report["details"]["sky_tracker_version"] == report["firmware"] != ""
    assert report["details"]["sky_commander_present"] is True


def test_a_bare_port_is_detected_as_a_sky_tracker_after_synscan_fails(
    config: Path, device: str
) -> None:
    result = scopelink(config, "info", device.removeprefix("skytracker:"), "--json")
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["protocol"] == "skytracker"


def test_what_the_box_cannot_do_is_one_line_with_a_hint(config: Path, device: str) -> None:
    result = scopelink(config, "goto", "--altaz", "40", "100", "--device", device)
    assert result.returncode == 1
    assert "cannot go to horizontal coordinates" in result.stderr
    assert "hint: 'scopelink info' shows what this mount can do" in result.stderr
    assert "Traceback" not in result.stderr
