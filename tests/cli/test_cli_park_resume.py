"""Issue #15 part 2 from the command line: ``scopelink park --axes``, the emulator switched off and
started again with ``--power-on-at`` where the tube was, and ``scopelink unpark`` puts the axis
positions back (docs/parking.md). Each command is its own process, as a user runs them."""

from __future__ import annotations

import json
import socket
from pathlib import Path
from typing import Any

from tests.support.cli import scopelink, separation_deg, state_of, synscan_emulator


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port: int = probe.getsockname()[1]
    return port


def _off_deg(state: dict[str, Any], other: dict[str, Any]) -> float:
    return separation_deg(state["alt_deg"], state["az_deg"], other["alt_deg"], other["az_deg"])


def test_park_then_power_on_elsewhere_then_unpark_restores_the_axes(config: Path) -> None:
    port = _free_port()  # the same port after the "power cycle": the same device, its records
    same_port = ("--no-pacing", "--tcp", f"127.0.0.1:{port}")
    with synscan_emulator(*same_port) as device:
        done = scopelink(config, "park", "--axes=10,80", "--device", device)
        assert done.returncode == 0, done.stderr
        assert "parked at" in done.stdout
        parked = state_of(config, device)
    [record_path] = (config.parent / "state").rglob("park.json")
    record = json.loads(record_path.read_text())
    assert record["axes_deg"] == [10.0, 80.0]

    power_on_at = f"{record['az_deg']},{record['alt_deg']}"  # the tube did not move meanwhile
    with synscan_emulator(*same_port, "--power-on-at", power_on_at) as device:
        before = state_of(config, device)
        assert not before["aligned"]
        assert _off_deg(before, parked) > 5.0  # the counters restarted at home
        done = scopelink(config, "unpark", "--device", device)
        assert done.returncode == 0, done.stderr
        assert "restored" in done.stdout
        after = state_of(config, device)
        assert _off_deg(after, parked) < 0.05
    assert not record_path.exists()  # used once


def test_a_bad_power_on_position_is_one_clear_line(config: Path) -> None:
    done = scopelink(config, "emulate", "synscan", "--power-on-at", "north")
    assert done.returncode == 2
    assert "azimuth,altitude" in done.stderr
    assert "Traceback" not in done.stderr


def test_the_park_position_in_the_settings_file(config: Path) -> None:
    done = scopelink(config, "config", "set", "park.altitude", "30", "park.azimuth", "200")
    assert done.returncode == 0, done.stderr
    done = scopelink(config, "park", "--device", "sim", "--clock-rate", "100")
    assert done.returncode == 0, done.stderr
    assert "Alt +30°00'00\" Az +200°00'00\"" in done.stdout
    bad = scopelink(config, "config", "set", "park.altitude", "-20")
    assert bad.returncode != 0
    assert "park" in bad.stderr
    assert "Traceback" not in bad.stderr
    assert len(bad.stderr.strip().splitlines()) <= 2  # the error and its hint


def test_config_show_reads_the_park_position_back(config: Path) -> None:
    done = scopelink(config, "config", "set", "park.altitude", "30", "park.azimuth", "200")
    assert done.returncode == 0, done.stderr
    shown = scopelink(config, "config", "show")
    assert "[park]\naltitude = 30.0\nazimuth = 200.0" in shown.stdout
