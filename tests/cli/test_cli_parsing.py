"""What the command line reads: targets, device strings, rates; every subcommand's help; ports."""

from __future__ import annotations

import argparse
import json
import time
from datetime import UTC, datetime
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from scopelink.astro import SIDEREAL_RATE_DEG_S, format_degrees, format_hours
from scopelink.cli.errors import CommandError
from scopelink.cli.goto_command import SlewDisplay
from scopelink.cli.main import build_parser
from scopelink.cli.motion_commands import parse_rate
from scopelink.cli.ports_command import SerialPort
from scopelink.cli.targets import AltAz, Named, RaDec, parse_target
from scopelink.drivers.open import DeviceOpenError, DeviceSpec, parse_device
from scopelink.mount import MountState, SlewProgress
from tests.support.cli import scopelink

# --- targets ---------------------------------------------------------------------------------

styles = st.sampled_from(["units", "colons", "spaces"])


@given(
    ra=st.floats(0.0, 23.999, allow_nan=False),
    dec=st.floats(-90.0, 90.0, allow_nan=False),
    style=styles,
    one_argument=st.booleans(),
)
def test_formatted_coordinates_read_back(
    ra: float, dec: float, style: str, one_argument: bool
) -> None:
    ra_text = format_hours(ra, decimals=2, style=style)  # type: ignore[arg-type]
    dec_text = format_degrees(dec, decimals=1, style=style)  # type: ignore[arg-type]
    words = [f"{ra_text} {dec_text}"] if one_argument else [ra_text, dec_text]
    target = parse_target(words)
    assert isinstance(target, RaDec)
    assert abs(((target.ra_hours - ra + 12) % 24) - 12) < 0.01 / 3600 + 1e-9
    assert target.dec_deg == pytest.approx(dec, abs=0.1 / 3600 + 1e-9)


@given(alt=st.floats(-90.0, 90.0), az=st.floats(0.0, 359.9))
def test_altaz_decimal_degrees_read_back(alt: float, az: float) -> None:
    target = parse_target([f"{alt:.5f}", f"{az:.5f}"], altaz=True)
    assert isinstance(target, AltAz)
    assert target.alt_deg == pytest.approx(alt, abs=1e-5)
    assert target.az_deg == pytest.approx(az, abs=1e-5)


@given(
    name=st.text(
        st.characters(whitelist_categories=("Lu", "Ll", "Nd", "Zs")), min_size=1, max_size=20
    ).filter(lambda text: text.strip() and text.strip()[0].isalpha())
)
def test_words_starting_with_a_letter_are_names(name: str) -> None:
    assert parse_target([name]) == Named(" ".join(name.split()))


@pytest.mark.parametrize(
    ("words", "expected"),
    [
        (["M31"], Named("M31")),
        (["HIP", "91262"], Named("HIP 91262")),
        (["NGC 7000"], Named("NGC 7000")),
        (
            ["05:35:17", "-05:23:28"],
            RaDec(5 + 35 / 60 + 17 / 3600, -(5 + 23 / 60 + 28 / 3600)),
        ),
        (["5.5 -5.25"], RaDec(5.5, -5.25)),
        (["5 30 00 -5 15 00"], RaDec(5.5, -5.25)),
        (["5h 30m 00s +5°15'00\""], RaDec(5.5, 5.25)),
        (["5 30 00 5 15 00"], RaDec(5.5, 5.25)),
    ],
)
def test_targets(words: list[str], expected: Named | RaDec) -> None:
    target = parse_target(words)
    if isinstance(expected, Named):
        assert target == expected
    else:
        assert isinstance(target, RaDec)
        assert target.ra_hours == pytest.approx(expected.ra_hours)
        assert target.dec_deg == pytest.approx(expected.dec_deg)


@pytest.mark.parametrize(
    ("words", "altaz"),
    [
        (["5.5"], False),
        (["1", "2", "3"], False),  # 1h and 2°3', or 1h2m and 3°?
        (["M31"], True),
        ([], False),
    ],
)
def test_unreadable_targets_are_command_errors(words: list[str], altaz: bool) -> None:
    with pytest.raises(CommandError):
        parse_target(words, altaz=altaz)


# --- device strings --------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("sim", DeviceSpec("sim", "eq6")),
        ("sim:AZ-GTi", DeviceSpec("sim", "az-gti")),
        ("synscan:/dev/ttyUSB0", DeviceSpec("synscan", "/dev/ttyUSB0")),
        ("SynScan:tcp://192.168.4.1:11880", DeviceSpec("synscan", "tcp://192.168.4.1:11880")),
        ("skytracker:/dev/ttyS1", DeviceSpec("skytracker", "/dev/ttyS1")),
        ("/dev/ttyUSB0", DeviceSpec(None, "/dev/ttyUSB0")),
        ("tcp://127.0.0.1:11880", DeviceSpec(None, "tcp://127.0.0.1:11880")),
        ("COM3", DeviceSpec(None, "COM3")),
    ],
)
def test_device_strings(text: str, expected: DeviceSpec) -> None:
    assert parse_device(text) == expected


@pytest.mark.parametrize("text", ["", "synscan:", "sim:eq7", "skytracker:  "])
def test_bad_device_strings_say_what_to_give(text: str) -> None:
    with pytest.raises(DeviceOpenError) as raised:
        parse_device(text)
    assert raised.value.hint


@given(
    kind=st.sampled_from(["synscan", "skytracker"]),
    link=st.from_regex(r"\A(/dev/tty[A-Za-z]{1,5}[0-9]{0,2}|tcp://[a-z0-9.]{1,20}:[0-9]{1,5})\Z"),
)
def test_device_strings_round_trip(kind: str, link: str) -> None:
    spec = parse_device(f"{kind}:{link}")
    assert spec == DeviceSpec(kind, link)
    assert parse_device(str(spec)) == spec


def test_a_port_that_does_not_exist_is_one_line_with_a_hint(tmp_path: Path) -> None:
    result = scopelink(
        tmp_path / "absent.toml", "status", "--device", f"synscan:{tmp_path}/ttyUSB9"
    )
    assert result.returncode == 1
    assert "cannot open" in result.stderr
    assert "hint: 'scopelink ports' lists the serial ports" in result.stderr
    assert "Traceback" not in result.stderr


# --- rates -----------------------------------------------------------------------------------


def test_rates() -> None:
    assert parse_rate("2") == 2.0
    assert parse_rate("-0.5") == -0.5
    assert parse_rate("16x") == pytest.approx(16 * SIDEREAL_RATE_DEG_S)
    assert parse_rate("-800X") == pytest.approx(-800 * SIDEREAL_RATE_DEG_S)
    with pytest.raises(CommandError):
        parse_rate("fast")


# --- help and ports --------------------------------------------------------------------------


def subcommand_parsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    actions = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(actions[0].choices)


def test_every_device_subcommand_has_help_with_examples_and_a_device_option() -> None:
    parsers = subcommand_parsers()
    device_commands = {"info", "status", "goto", "sync", "move", "stop", "track", "park"}
    device_commands |= {"unpark", "guide", "time", "site"}
    assert device_commands | {"ports", "config"} <= set(parsers)
    for name in device_commands:
        text = parsers[name].format_help()
        assert "examples:" in text, name
        assert "--device DEVICE" in text, name
        assert "-v, --verbose" in text, name


def test_ports_lists_and_flags() -> None:
    prolific = SerialPort("/dev/ttyUSB0", "USB-Serial", 0x067B, 0x2303, None, "Prolific")
    other = SerialPort("/dev/ttyACM0", "Arduino", 0x2341, 0x0043, None, None)
    assert prolific.adapter is not None
    assert "PL2303" in prolific.adapter
    assert prolific.usb_id == "067b:2303"
    assert other.adapter is None


def test_ports_runs(tmp_path: Path) -> None:
    listed = scopelink(tmp_path / "absent.toml", "ports", "--json")
    assert listed.returncode == 0, listed.stderr
    ports = json.loads(listed.stdout)
    assert isinstance(ports, list)
    assert all({"device", "usb_id", "likely_hand_control"} <= set(port) for port in ports)


@pytest.mark.parametrize("command", ["goto", "sync"])
@pytest.mark.parametrize("dec", ["-05:23:28", "-5°23'28\"", "-05 23 28", "-5.3911"])
def test_a_negative_declination_is_an_argument_not_an_option(command: str, dec: str) -> None:
    args = build_parser().parse_args([command, "05:35:17", dec, "-d", "sim"])
    assert args.target == ["05:35:17", dec]
    assert args.device == "sim"
    target = parse_target(args.target)
    assert isinstance(target, RaDec)
    assert target.dec_deg == pytest.approx(-5.3911, abs=1e-3)


def test_a_negative_rate_in_sidereal_multiples_is_an_argument() -> None:
    args = build_parser().parse_args(["move", "dec", "-16x", "--for", "2"])
    assert (args.rate, args.seconds) == ("-16x", 2.0)


def test_unknown_options_are_still_refused() -> None:
    with pytest.raises(SystemExit):
        build_parser().parse_args(["goto", "M31", "-x"])


# --- slew progress lines ---------------------------------------------------------------------


def test_progress_lines_and_a_position_that_stops_updating(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """Without a terminal: a line a second on stderr; a slewing mount whose position stays put
    (a Sky Tracker during GOTO) is flagged."""
    at = datetime(2026, 1, 1, tzinfo=UTC)
    slewing = MountState(read_at=at, connected=True, slewing=True)
    with SlewDisplay("M 31", stale_after_s=0.05) as display:
        display.update(SlewProgress(slewing, 12.345, 4.2))
        first = capsys.readouterr().err
        time.sleep(0.1)
        display.update(SlewProgress(slewing, 12.345, None))  # within the second: not printed
        assert capsys.readouterr().err == ""
        time.sleep(1.0)
        display.update(SlewProgress(slewing, 12.345, None))
        later = capsys.readouterr().err
    assert first == "M 31: 12.35° to go, ETA 4 s\n"
    assert later == "M 31: 12.35° to go (position not updating)\n"
