"""``scopelink track`` following moving targets on ``--device sim`` (accelerated clock): the live
view on a terminal and a clean Ctrl-C, a comet from an elements file for --duration, and the
refusals in one line (issue #16)."""

from __future__ import annotations

import os
import pty
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

from scopelink.astro import now
from scopelink.astro.targets import orbit_target, solar_system_target
from tests.support.cli import environment, scopelink, scopelink_here
from tests.support.targets import COMETS, site_under


def _site_option(ra_hours: float, dec_deg: float) -> str:
    site = site_under(ra_hours, dec_deg, now())
    return f"--site={site.latitude_deg:.4f},{site.longitude_deg:.4f}"


def _read_until(fd: int, marker: bytes, seen: bytes, timeout_s: float) -> bytes:
    deadline = time.monotonic() + timeout_s
    while marker not in seen and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.5)
        if ready:
            try:
                chunk = os.read(fd, 4096)
            except OSError:
                break
            if not chunk:
                break
            seen += chunk
    return seen


def test_moon_live_view_on_a_terminal_and_ctrl_c_stops_cleanly(config: Path) -> None:
    site = _site_option(*solar_system_target("Moon", None).position(now()))
    controller, terminal = pty.openpty()
    command = ["track", "moon", "--device", "sim", "--clock-rate", "50", site]
    process = subprocess.Popen(
        [sys.executable, "-m", "scopelink", *command],
        stdin=subprocess.DEVNULL,
        stdout=terminal,
        stderr=terminal,
        env=environment(config),
    )
    os.close(terminal)
    try:
        seen = _read_until(controller, "″/s".encode(), b"", 40.0)
        assert b"following Moon (moon)" in seen, seen
        assert b"Moon: following, error" in seen, seen
        assert b"\x1b[" in seen  # drawn live, not in plain lines
        process.send_signal(signal.SIGINT)
        assert process.wait(timeout=20) == 0
        seen = _read_until(controller, b"rates back to zero", seen, 5.0)
        text = seen.decode(errors="replace")
        assert "followed Moon for" in text
        assert "stopped; rates back to zero" in text
        assert "Traceback" not in text
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
        os.close(controller)


def test_a_comet_from_an_elements_file_for_a_duration(config: Path) -> None:
    comet = orbit_target("C/2023 A3", COMETS, None)
    site = _site_option(*comet.position(now()))
    result = scopelink(
        config,
        *("track", "comet", "C/2023 A3", "--elements", str(COMETS), "--device", "sim"),
        *("--clock-rate", "100", "--duration", "200", site),
    )
    assert result.returncode == 0, result.stderr
    assert "following C/2023 A3 (Tsuchinshan-ATLAS) (comet)" in result.stdout
    summary = result.stdout.strip().splitlines()[-1]
    assert summary.startswith("followed C/2023 A3 (Tsuchinshan-ATLAS) for ")
    assert "time is up; rates back to zero" in summary
    rms = float(summary.split("tracking error ")[1].split("″")[0])
    assert rms < 30.0, summary  # the goto's landing error included; closed within a minute
    assert "C/2023 A3 (Tsuchinshan-ATLAS): following, error" in result.stderr  # a line a second


def test_refusals_are_one_line(config: Path, tmp_path: Path) -> None:
    sun_site = _site_option(*solar_system_target("Sun", None).position(now()))
    status, _, err = scopelink_here(config, "track", "sun", "--device", "sim", sun_site)
    assert status != 0
    assert "tracking the Sun needs Sun avoidance off" in err
    assert "limits.sun_avoidance_deg = 0" in err
    status, _, err = scopelink_here(config, "track", "comet", "C/2023 A3", "--device", "sim")
    assert status != 0
    assert "track comet needs --elements FILE" in err
    bad = tmp_path / "bad.tle"
    bad.write_text("ISS\n1 25544U 98067A\n")
    status, _, err = scopelink_here(
        config, "track", "satellite", "ISS", "--tle", str(bad), "--device", "sim"
    )
    assert status != 0
    assert "line 2: not line 1 of a TLE" in err
    assert err.startswith("scopelink track: ")
    assert len(err.strip().splitlines()) == 1
