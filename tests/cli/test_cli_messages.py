"""The CLI's messages for people (issue #18 part 6), each from ``scopelink`` run as a subprocess:
"did you mean" for a mistyped command, flag or device kind, one-line errors with the fix, human
``info`` output, ``config set`` confirmations, ``config init`` writing nothing active, plain
warnings. Every one is read from what a user sees: the exit status, stdout and stderr."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest

from scopelink.cli.config import load_config
from tests.support.cli import scopelink
from tests.support.serve import run_serve


def assert_no_traceback(stderr: str) -> None:
    assert "Traceback" not in stderr, stderr
    assert "Error:" not in stderr.replace("error:", ""), stderr  # no exception class names


@pytest.mark.parametrize(
    ("args", "usage", "suggestion"),
    [
        (("stauts",), "usage: scopelink [", "did you mean status?"),
        (("serve", "--devcie", "sim"), "usage: scopelink serve", "did you mean --device?"),
        (("status", "--jsn"), "usage: scopelink status", "did you mean --json?"),
        (("config", "shwo"), "usage: scopelink config", "did you mean show?"),
        (("track", "sideral"), "usage: scopelink track", "did you mean sidereal?"),
    ],
)
def test_a_mistyped_command_or_flag_gets_its_usage_and_a_suggestion(
    config: Path, args: tuple[str, ...], usage: str, suggestion: str
) -> None:
    result = scopelink(config, *args)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith(usage), result.stderr
    assert suggestion in result.stderr
    assert_no_traceback(result.stderr)


@pytest.mark.parametrize(
    ("device", "suggestion"),
    [
        ("simm", "did you mean sim?"),
        ("synscn:/dev/ttyUSB0", "did you mean synscan:/dev/ttyUSB0?"),
        ("SkyTraker:COM3", "did you mean skytracker:COM3?"),
        ("skycomander:/dev/ttyUSB1", "did you mean skycommander:/dev/ttyUSB1?"),
    ],
)
def test_a_mistyped_device_kind_is_not_opened_as_a_port(
    config: Path, device: str, suggestion: str
) -> None:
    result = scopelink(config, "status", "--device", device)
    assert result.returncode == 1
    lines = result.stderr.splitlines()
    assert lines[0].startswith("scopelink status: unknown device kind"), result.stderr
    assert lines[0].endswith(suggestion)
    assert lines[1].startswith("  hint: device kinds: sim, synscan, skytracker, skycommander")
    assert len(lines) == 2, result.stderr
    assert "cannot open" not in result.stderr  # it was never taken for a port


def test_info_is_written_for_people_and_json_for_scripts(config: Path) -> None:
    human = scopelink(config, "info", "sim")
    assert human.returncode == 0, human.stderr
    lines = [" ".join(line.split()) for line in human.stdout.splitlines()]
    assert "max axis rate 3.34°/s" in lines
    assert "manual motion both axes" in lines
    assert "aligned yes" in lines
    assert "capabilities" not in human.stdout
    assert "deg s" not in human.stdout
    assert "True" not in human.stdout
    scripted = scopelink(config, "info", "sim", "--json")
    assert scripted.returncode == 0, scripted.stderr
    report = json.loads(scripted.stdout)
    assert report["capabilities"]["max_axis_rate_deg_s"] == pytest.approx(3.3425, abs=1e-3)
    assert report["capabilities"]["can_move_axis"] == [True, True]


def test_config_set_says_what_it_changed_as_the_user_named_it(tmp_path: Path) -> None:
    config = tmp_path / "config.toml"
    first = scopelink(config, "config", "set", "site.latitude", "40.4", "site.longitude", "-3.7")
    assert first.returncode == 0, first.stderr
    assert first.stdout.splitlines()[:2] == [
        "site.latitude: (default) -> 40.4",
        "site.longitude: (default) -> -3.7",
    ]
    second = scopelink(config, "config", "set", "site.latitude", "41.0")
    assert second.stdout.splitlines()[0] == "site.latitude: 40.4 -> 41.0"
    before = config.read_bytes()
    refused = scopelink(config, "config", "set", "site.latitude", "100")
    assert refused.returncode == 1
    first_line = refused.stderr.splitlines()[0]
    assert "site.latitude: must be in [-90, 90] (north positive), got 100" in first_line
    assert "latitude_deg" not in refused.stderr
    assert "Site." not in refused.stderr
    assert "is unchanged" in refused.stderr
    assert config.read_bytes() == before
    removed = scopelink(config, "config", "unset", "site")
    assert removed.stdout.splitlines()[0].startswith("site: {'latitude': 41.0")
    assert removed.stdout.splitlines()[0].endswith("-> (default)")


def test_config_init_writes_the_example_with_nothing_active(tmp_path: Path) -> None:
    config = tmp_path / "config.toml"
    result = scopelink(config, "config", "init")
    assert result.returncode == 0, result.stderr
    assert "commented out" in result.stdout
    text = config.read_text(encoding="utf-8")
    assert tomllib.loads(text) == {}  # no Madrid site, no 10° horizon until the user says so
    assert "# latitude = 40.4" in text
    assert "# altitude = 10" in text
    assert load_config(config).site_configured is False
    shown = scopelink(config, "config", "show")
    assert "# default: Greenwich" in shown.stdout


def test_warnings_are_sentences_not_logger_lines(tmp_path: Path) -> None:
    """``serve`` on a port that does not exist warns before each retry; the warning is a plain
    sentence, and the final error one line with its hint."""
    result = run_serve(tmp_path, "--device", f"synscan:{tmp_path}/ttyUSB9")
    assert result.returncode == 1, result.stderr
    warnings = [line for line in result.stderr.splitlines() if "trying again" in line]
    assert len(warnings) == 2, result.stderr
    for line in warnings:
        assert line.startswith("scopelink: warning: "), line
        assert "scopelink.cli" not in line
        assert "WARNING" not in line
    assert_no_traceback(result.stderr)


@pytest.mark.parametrize(
    ("device", "hint"),
    [
        ("synscan:{tmp}/ttyUSB9", "hint: 'scopelink ports' lists the serial ports"),
        ("{tmp}/ttyUSB9", "hint: 'scopelink ports' lists the serial ports"),  # autodetect
        ("tcp://127.0.0.1:1", "hint: check the address and port"),
    ],
)
def test_a_port_that_will_not_open_is_said_once(tmp_path: Path, device: str, hint: str) -> None:
    """Each layer's "cannot open" is not repeated, and autodetect does not try a second kind on
    a port that did not open: one line, one hint for that kind of link."""
    result = scopelink(tmp_path / "absent.toml", "status", "--device", device.format(tmp=tmp_path))
    assert result.returncode == 1
    lines = result.stderr.splitlines()
    assert len(lines) == 2, result.stderr
    assert lines[0].startswith("scopelink status: cannot open "), lines[0]
    assert lines[0].count("cannot open") == 1, lines[0]
    assert "skytracker" not in lines[0]
    assert lines[1].startswith("  " + hint), lines[1]


def test_a_path_given_to_decode_as_bytes_gets_the_file_option(config: Path) -> None:
    result = scopelink(config, "decode", "/var/log/trace.txt")
    assert result.returncode == 1
    assert result.stderr.splitlines()[-1] == "  hint: to decode a file, give --file PATH"
    assert_no_traceback(result.stderr)
