"""The device commands against the built-in simulated mount (``--device sim``), as subprocesses."""

from __future__ import annotations

import json
import os
import pty
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from scopelink.cli.main import main
from tests.support.cli import degrees_in, environment, scopelink

GREENWICH_LATITUDE = 51.4779


@pytest.fixture
def config(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A settings file that does not exist: every default (for subprocesses and in-process)."""
    path = tmp_path / "absent.toml"
    monkeypatch.setenv("SCOPELINK_CONFIG", str(path))
    return path


def run_here(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """``scopelink ARGS`` in this process (cheaper than a subprocess for quick commands)."""
    status = main(list(args))
    out, err = capsys.readouterr()
    return status, out, err


def test_status_json_shows_the_power_on_position(config: Path) -> None:
    result = scopelink(config, "status", "--json", "--device", "sim")
    assert result.returncode == 0, result.stderr
    state = json.loads(result.stdout)
    assert state["connected"] is True
    # Power-on: counterweight down, pointing at the pole, whose altitude is the latitude.
    assert state["alt_deg"] == pytest.approx(GREENWICH_LATITUDE, abs=0.01)
    assert state["slewing"] is False
    assert state["tracking"] == "off"
    assert state["pier_side"] in {"east", "west"}


def test_status_table_has_every_row(config: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run_here(capsys, "status", "--device", "sim:heq5")
    assert status == 0, err
    for label in ("RA / Dec J2000", "RA / Dec of date", "Alt / Az", "pier side", "slewing"):
        assert label in out
    assert "HEQ5" in out


def test_goto_altaz_arrives_and_reports_progress(config: Path) -> None:
    result = scopelink(
        config, "goto", "--altaz", "40", "150", "--device", "sim", "--clock-rate", "50"
    )
    assert result.returncode == 0, result.stderr
    assert "slewing to Alt 40° Az 150°" in result.stdout
    arrived = result.stdout.split("arrived:")[1]
    assert degrees_in(arrived, "Alt") == pytest.approx(40.0, abs=0.02)
    assert degrees_in(arrived, "Az") == pytest.approx(150.0, abs=0.02)
    assert "° to go" in result.stderr  # progress lines (no terminal: one a second)


def test_goto_by_name_reaches_the_object(config: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Polaris is always up at Greenwich, so the test does not depend on the hour it runs.
    status, out, err = run_here(capsys, "goto", "Polaris", "--device", "sim", "--clock-rate", "30")
    assert status == 0, err
    assert "slewing to Polaris" in out
    assert degrees_in(out.split("arrived:")[1], "Dec") == pytest.approx(89.264, abs=0.01)


def test_goto_below_the_horizon_is_refused_with_one_line(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, _, err = run_here(capsys, "goto", "--altaz", "-5", "100", "--device", "sim")
    assert status == 1
    message, hint = err.strip().splitlines()
    assert message.startswith("scopelink goto: target is at altitude -5.00°")
    assert "below the configured horizon" in message
    assert "nothing was sent" in message
    assert hint.startswith("  hint: the horizon and limits are set in the config file")


def test_goto_an_unknown_name_suggests(config: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, _, err = run_here(capsys, "goto", "Vegaa", "--device", "sim")
    assert status == 1
    assert "no object named 'Vegaa'" in err
    assert "Vega" in err


def test_move_for_a_time_turns_the_axis_then_stops(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run_here(capsys, "move", "az", "2", "--for", "0.5", "--device", "sim:az-gti")
    assert status == 0, err
    assert "moving the primary axis at +2.0000°/s for 0.5 s" in out
    # An alt-az mount starts level pointing north: 0.5 s at 2°/s (with ramps) leaves it east of 0.
    azimuth = degrees_in(out.split("stopped at")[1], "Az")
    # 1.0° at most on time; a loaded machine may stop it late, but 3° would be --for ignored.
    assert 0.2 < azimuth < 3.0


def test_track_on_picks_the_mode_the_geometry_needs(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert run_here(capsys, "track", "on", "--device", "sim")[:2] == (0, "tracking: sidereal\n")
    assert run_here(capsys, "track", "on", "--device", "sim:az-gti")[:2] == (
        0,
        "tracking: altaz\n",
    )


def test_an_unsupported_tracking_mode_is_one_line_with_a_hint(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, _, err = run_here(capsys, "track", "altaz", "--device", "sim")
    assert status == 1
    assert "tracking mode 'altaz' is not supported" in err
    assert "hint: 'scopelink info'" in err


def test_park_guide_time_and_site(config: Path, capsys: pytest.CaptureFixture[str]) -> None:
    status, out, err = run_here(capsys, "park", "--device", "sim")
    assert (status, out[:9]) == (0, "parked at"), err
    status, out, err = run_here(capsys, "guide", "n", "200", "--device", "sim")
    assert (status, out) == (0, "guided north for 200 ms\n"), err
    status, out, err = run_here(capsys, "time", "--device", "sim")
    assert (status, out[:18]) == (0, "mount clock set to"), err
    status, out, err = run_here(capsys, "site", "--site", "40.4,-3.7", "--device", "sim")
    assert status == 0, err
    assert "latitude +40.4000°, longitude -3.7000°" in out


def test_site_refuses_to_push_the_default_site(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, _, err = run_here(capsys, "site", "--device", "sim")
    assert status == 1
    assert "no site configured" in err


def test_info_describes_the_simulated_mount(
    config: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    status, out, err = run_here(capsys, "info", "sim:az-gti", "--json")
    assert status == 0, err
    report = json.loads(out)
    assert report["protocol"] == "simulator"
    assert report["model"] == "AZ-GTi"
    assert report["capabilities"]["alignment_mode"] == "altaz"
    assert "altaz" in report["capabilities"]["tracking_modes"]


def test_on_a_terminal_goto_draws_a_progress_bar_and_ctrl_c_stops(config: Path) -> None:
    """stdout and stderr on a real pseudo-terminal: rich draws the bar; SIGINT aborts."""
    controller, terminal = pty.openpty()
    process = subprocess.Popen(
        [sys.executable, "-m", "scopelink", "goto", "--altaz", "30", "250", "--device", "sim"],
        stdin=subprocess.DEVNULL,
        stdout=terminal,
        stderr=terminal,
        env=environment(config),
    )
    os.close(terminal)
    seen = b""
    try:
        deadline = time.monotonic() + 30
        while b"ETA" not in seen and time.monotonic() < deadline:
            ready, _, _ = select.select([controller], [], [], 1.0)
            if ready:
                seen += os.read(controller, 4096)
        assert b"ETA" in seen, seen
        assert "° to go".encode() in seen
        assert b"\x1b[" in seen  # drawn with terminal control sequences, not plain lines
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20) == 130
        while True:
            ready, _, _ = select.select([controller], [], [], 1.0)
            if not ready:
                break
            try:
                chunk = os.read(controller, 4096)
            except OSError:  # the terminal closed with the process
                break
            if not chunk:
                break
            seen += chunk
        assert b"slew aborted" in seen
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        os.close(controller)
