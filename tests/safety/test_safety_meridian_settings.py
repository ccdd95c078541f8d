"""The meridian limits' settings (``[limits]`` in the settings file, ``scopelink config set``)
and their documented defaults against the code (issue #15 part 3; docs/meridian.md)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from scopelink.cli.config import parse_config
from scopelink.cli.config_command import EXAMPLE_CONFIG
from scopelink.mount import Limits
from scopelink.mount.limits import (
    DEFAULT_MERIDIAN_DEG,
    DEFAULT_MIN_TRACK_MINUTES,
    MAX_MERIDIAN_DEG,
    MAX_MIN_TRACK_MINUTES,
)

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs" / "meridian.md"


def test_the_settings_file_reads_and_checks_the_meridian_keys(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    text = (
        "[limits]\nmeridian_west_deg = 8\nmeridian_east_deg = 2.5\n"
        "min_track_minutes = 30\nauto_flip = true\n"
    )
    limits = parse_config(text, path).limits
    assert (limits.meridian_west_deg, limits.meridian_east_deg) == (8.0, 2.5)
    assert limits.min_track_minutes == 30.0
    assert limits.auto_flip is True
    with pytest.raises(Exception, match=r"limits\.meridian_west_deg: .* between 0° and 45°"):
        parse_config("[limits]\nmeridian_west_deg = 50\n", path)
    with pytest.raises(Exception, match=r"limits\.auto_flip: expected true or false"):
        parse_config('[limits]\nauto_flip = "yes"\n', path)


def test_config_set_refuses_a_bad_value_and_keeps_the_file(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    command = [sys.executable, "-m", "scopelink", "config", "set"]
    env = {"SCOPELINK_CONFIG": str(path), "PATH": "/usr/bin:/bin"}
    ok = subprocess.run(
        [*command, "limits.meridian_west_deg", "7.5", "limits.auto_flip", "true"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert ok.returncode == 0, ok.stderr
    before = path.read_text()
    bad = subprocess.run(
        [*command, "limits.min_track_minutes", "999"],
        env=env,
        capture_output=True,
        text=True,
        check=False,
    )
    assert bad.returncode != 0
    assert "limits.min_track_minutes" in bad.stderr
    assert "Traceback" not in bad.stderr
    assert path.read_text() == before
    assert parse_config(before, path).limits.meridian_west_deg == 7.5


def test_the_documented_defaults_are_the_code_defaults() -> None:
    docs = DOCS.read_text(encoding="utf-8")
    limits = Limits()
    rows = {
        "limits.meridian_west_deg": f"**{DEFAULT_MERIDIAN_DEG:g}°** | 0-{MAX_MERIDIAN_DEG:g}°",
        "limits.meridian_east_deg": f"**{DEFAULT_MERIDIAN_DEG:g}°** | 0-{MAX_MERIDIAN_DEG:g}°",
        "limits.min_track_minutes": (
            f"**{DEFAULT_MIN_TRACK_MINUTES:g} min** | 0-{MAX_MIN_TRACK_MINUTES:g} min"
        ),
        "limits.auto_flip": "**false**",
    }
    for setting, cells in rows.items():
        assert f"| `{setting}` | {cells} |" in docs, setting
    assert limits.meridian_west_deg == limits.meridian_east_deg == DEFAULT_MERIDIAN_DEG
    assert limits.min_track_minutes == DEFAULT_MIN_TRACK_MINUTES
    assert limits.auto_flip is False
    cli = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    for text in (cli, EXAMPLE_CONFIG):
        assert re.search(rf"meridian_west_deg = {DEFAULT_MERIDIAN_DEG:g}\b", text)
        assert re.search(rf"meridian_east_deg = {DEFAULT_MERIDIAN_DEG:g}\b", text)
        assert re.search(rf"min_track_minutes = {DEFAULT_MIN_TRACK_MINUTES:g}\b", text)
        assert "auto_flip = false" in text
    assert "meridian.md" in (ROOT / "docs" / "mount-api.md").read_text(encoding="utf-8")
