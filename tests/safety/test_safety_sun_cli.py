"""``scopelink goto Sun`` as a user runs it (a subprocess, the simulator on the PC's clock), the
setting in the settings file, and the docs agreeing with the code on its default.

The subprocess reads the PC's clock, so the site is chosen at test time to put the Sun on the
meridian 55° up: wherever and whenever the test runs, the Sun is at a known place.
"""

from __future__ import annotations

import re
from datetime import UTC, datetime
from pathlib import Path

from scopelink.astro import Site, gast_hours, j2000_to_apparent
from scopelink.cli.config import load_config
from scopelink.cli.config_command import EXAMPLE_CONFIG
from scopelink.mount.limits import SUN_AVOIDANCE_DEG
from scopelink.mount.sun import sun_j2000
from tests.support.cli import scopelink

DOCS = Path(__file__).resolve().parents[2] / "docs"


def sunny_site() -> tuple[float, float]:
    """A latitude and longitude where the Sun now transits 55° up."""
    now = datetime.now(UTC)
    ra, dec = j2000_to_apparent(*sun_j2000(now, Site(0.0, 0.0)), now)
    latitude = dec + 35.0 if dec + 35.0 <= 80.0 else dec - 35.0
    longitude = (15.0 * (ra - gast_hours(now)) + 180.0) % 360.0 - 180.0
    return latitude, longitude


def settings(tmp_path: Path, extra: str = "") -> Path:
    latitude, longitude = sunny_site()
    config = tmp_path / "config.toml"
    config.write_text(
        f'device = "sim"\n[site]\nlatitude = {latitude:.4f}\nlongitude = {longitude:.4f}\n' + extra,
        encoding="utf-8",
    )
    return config


def test_cli_goto_sun_exits_1_with_one_line(tmp_path: Path) -> None:
    """The reproduction: before Sun avoidance this slewed and exited 0."""
    result = scopelink(settings(tmp_path), "goto", "Sun", "--no-wait")
    assert result.returncode == 1, result.stderr
    lines = [line for line in result.stderr.splitlines() if line.strip()]
    assert "Sun avoidance zone (limits.sun_avoidance_deg)" in lines[0]
    assert "Traceback" not in result.stderr
    assert "limits.sun_avoidance_deg in the config file" in result.stderr  # the hint


def test_cli_with_the_zone_off_warns_in_red_and_obeys(tmp_path: Path) -> None:
    config = settings(tmp_path, "[limits]\nsun_avoidance_deg = 0\n")
    result = scopelink(config, "goto", "Sun", "--no-wait")
    assert result.returncode == 0, result.stderr
    assert "warning: Sun avoidance is OFF (limits.sun_avoidance_deg = 0)" in result.stderr


def test_bad_setting_names_the_key(tmp_path: Path) -> None:
    config = settings(tmp_path, "[limits]\nsun_avoidance_deg = 90\n")
    result = scopelink(config, "status")
    assert result.returncode == 1
    assert "limits.sun_avoidance_deg" in result.stderr
    assert "Sun avoidance radius 90.0° must lie between 0° (off) and 45°" in result.stderr


def test_docs_and_example_agree_with_the_default(tmp_path: Path) -> None:
    assert load_config(tmp_path / "missing.toml").limits.sun_avoidance_deg == SUN_AVOIDANCE_DEG
    path = tmp_path / "example.toml"
    path.write_text(EXAMPLE_CONFIG, encoding="utf-8")
    assert load_config(path).limits.sun_avoidance_deg == SUN_AVOIDANCE_DEG
    assert re.search(rf"sun_avoidance_deg = {SUN_AVOIDANCE_DEG:g}\b", EXAMPLE_CONFIG)
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert re.search(rf"sun_avoidance_deg = {SUN_AVOIDANCE_DEG:g}\b", cli)
    safety = (DOCS / "reliability-safety.md").read_text(encoding="utf-8")
    assert f"`limits.sun_avoidance_deg` (default {SUN_AVOIDANCE_DEG:g}°" in safety
