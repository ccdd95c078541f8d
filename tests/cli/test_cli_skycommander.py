"""``scopelink skycommander`` as a user runs it (subprocesses) against the Sky Commander emulator
alone and the Sky Tracker emulator: uploads land in the emulated EEPROM, plan files fail whole,
``clear`` and ``slots`` keep the mirror honest, and ``pushto`` agrees with the box's offsets."""

from __future__ import annotations

import asyncio
import re
import signal
import subprocess
import sys
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path

import pytest

from scopelink.astro.catalog import lookup
from scopelink.links import open_link
from scopelink.protocol.skytracker import LoadObject, OffsetsReply, ReadOffsets
from scopelink.servers.skytracker.objects import ObjectStore, StoredObject
from tests.support.cli import RUN_TIMEOUT_S, emulator, environment
from tests.support.skytracker_emulator import CommanderSession


@pytest.fixture
def state_dir(tmp_path: Path) -> Path:
    return tmp_path / "state"


@pytest.fixture
def box(tmp_path: Path) -> Iterator[tuple[str, Path]]:
    """A Sky Commander emulator alone on TCP (subprocess); its device string and EEPROM dir."""
    data = tmp_path / "eeprom"
    with emulator("skycommander", "--no-pacing", "--data-dir", str(data)) as device:
        yield device, data


def run(config: Path, state_dir: Path, *args: str) -> subprocess.CompletedProcess[str]:
    """``scopelink skycommander ARGS`` with its own state directory (the mirror)."""
    env = {**environment(config), "XDG_STATE_HOME": str(state_dir)}
    return subprocess.run(
        [sys.executable, "-m", "scopelink", "skycommander", *args],
        env=env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=RUN_TIMEOUT_S,
        check=False,
    )


def eeprom(data: Path) -> dict[int, StoredObject]:
    return ObjectStore(data).items()


def test_upload_names_lands_in_the_eeprom_and_the_mirror(
    config: Path, state_dir: Path, box: tuple[str, Path]
) -> None:
    device, data = box
    result = run(config, state_dir, "upload", "M", "31", "NGC 7000", "Vega", "-d", device)
    assert result.returncode == 0, result.stderr
    assert "3 object(s) stored" in result.stdout
    stored = eeprom(data)
    assert sorted(stored) == [0, 1, 2]
    assert stored[0].ra_hours == pytest.approx(0.712, abs=0.001)  # M 31
    assert stored[0].dec_degrees == pytest.approx(41.269, abs=0.001)
    assert stored[1].ra_hours == pytest.approx(20.988, abs=0.002)  # NGC 7000
    assert stored[2].dec_degrees == pytest.approx(38.78, abs=0.01)  # Vega
    shown = run(config, state_dir, "slots", "-d", device)
    assert shown.returncode == 0, shown.stderr
    lines = shown.stdout.splitlines()
    assert lines[0].startswith("00  M 31")
    assert lines[1].startswith("01  NGC 7000")
    assert lines[2].startswith("02  Vega")
    assert "3 of 59 slots" in shown.stdout


def test_a_plan_file_with_slots_and_a_comets_positions(
    config: Path, state_dir: Path, box: tuple[str, Path], tmp_path: Path
) -> None:
    device, data = box
    plan = tmp_path / "tonight.txt"
    plan.write_text(
        "# Friday\n"
        "M 42\n"
        "@20 M 13   # the cluster\n"
        "18:10:00 +20:30:00 = C/2026 X1 at 20h\n"
        "18.2 +20.9 = C/2026 X1 at 22h\n"
        "\n",
        encoding="utf-8",
    )
    result = run(config, state_dir, "upload", "--plan", str(plan), "--from", "10", "-d", device)
    assert result.returncode == 0, result.stderr
    stored = eeprom(data)
    assert sorted(stored) == [10, 20, 21, 22]
    assert stored[21] == StoredObject(18.167, 20.5)  # 18:10:00 on the wire: 3 decimals
    assert stored[22] == StoredObject(18.2, 20.9)
    shown = run(config, state_dir, "slots", "-d", device).stdout
    assert re.search(r"^21  C/2026 X1 at 20h", shown, re.MULTILINE)


@pytest.mark.parametrize(
    "case",
    [
        ("M 31\nM 99999\n", "line 2: no object named 'M 99999'"),
        ("M 31\n\n12:00 +95:00\n", "line 3: cannot read '12:00 +95:00'"),
        ("@57 M 31\nM 32\nM 33\n", "line 3: slot 59 is past the last one (58)"),
        ("@5 M 31\n@5 M 32\n", "line 2: slot 05 is already taken by line 1"),
        ("M 31\n@xx M 32\n", "line 2: a slot is '@NN'"),
        ("M 31\nSun\n", "line 2: Sun is 0.0° from the Sun"),
        ("# nothing\n", "the plan holds no object"),
    ],
)
def test_a_bad_plan_line_is_named_and_nothing_is_uploaded(
    config: Path, state_dir: Path, box: tuple[str, Path], tmp_path: Path, case: tuple[str, str]
) -> None:
    device, data = box
    plan, message = case
    path = tmp_path / "plan.txt"
    path.write_text(plan, encoding="utf-8")
    result = run(config, state_dir, "upload", "--plan", str(path), "-d", device)
    assert result.returncode == 1
    assert message in result.stderr
    assert "nothing uploaded" in result.stderr
    assert "Traceback" not in result.stderr
    assert eeprom(data) == {}
    assert "written no slot" in run(config, state_dir, "slots", "-d", device).stdout


def test_more_objects_than_slots_left_are_refused_whole(
    config: Path, state_dir: Path, box: tuple[str, Path]
) -> None:
    device, data = box
    result = run(config, state_dir, "upload", "M1", "M2", "M3", "--from", "57", "-d", device)
    assert result.returncode == 1
    assert "argument 3 ('M3'): slot 59 is past the last one" in result.stderr
    assert eeprom(data) == {}
    result = run(config, state_dir, "upload", "M1", "--from", "59", "-d", device)
    assert result.returncode == 1
    assert "--from 59" in result.stderr


def test_clear_writes_the_pole_over_what_scopelink_wrote(
    config: Path, state_dir: Path, box: tuple[str, Path]
) -> None:
    device, data = box
    assert (
        run(config, state_dir, "upload", "M 31", "M 42", "--from", "3", "-d", device).returncode
        == 0
    )
    asyncio.run(key_in(device, 30, 1.0, 2.0))  # an object of the user's own, not scopelink's
    forgot = run(config, state_dir, "clear", "4", "--forget", "-d", device)
    assert forgot.returncode == 0, forgot.stderr
    assert eeprom(data)[4] != StoredObject(0.0, 90.0)  # --forget sends nothing
    cleared = run(config, state_dir, "clear", "-d", device)
    assert cleared.returncode == 0, cleared.stderr
    assert "cleared 1 slot(s)" in cleared.stdout
    stored = eeprom(data)
    assert stored[3] == StoredObject(0.0, 90.0)
    assert stored[4] != StoredObject(0.0, 90.0)  # forgotten, so not scopelink's to clear
    assert stored[30] == StoredObject(1.0, 2.0)  # the user's own slot is left alone
    assert "written no slot" in run(config, state_dir, "slots", "-d", device).stdout


def test_devices_without_a_sky_commander_are_refused(config: Path, state_dir: Path) -> None:
    result = run(config, state_dir, "upload", "M31", "-d", "sim")
    assert result.returncode == 1
    assert "has no Sky Commander" in result.stderr
    assert "hint: name it skycommander:PORT" in result.stderr


def test_upload_through_the_sky_trackers_bus(config: Path, state_dir: Path, tmp_path: Path) -> None:
    data = tmp_path / "tracker-eeprom"
    with emulator("skytracker", "--no-pacing", "--data-dir", str(data)) as device:
        result = run(config, state_dir, "upload", "M 57", "--from", "40", "-d", device)
        assert result.returncode == 0, result.stderr
    assert sorted(eeprom(data)) == [40]
    assert eeprom(data)[40].dec_degrees == pytest.approx(33.03, abs=0.01)


_FIGURES = re.compile(r"altitude (up|down) ([0-9.]+)°, azimuth (left|right) ([0-9.]+)°")


def figures(line: str) -> tuple[float, float]:
    match = _FIGURES.search(line)
    assert match, line
    up = float(match.group(2)) * (1 if match.group(1) == "up" else -1)
    right = float(match.group(4)) * (1 if match.group(3) == "right" else -1)
    return up, right


async def key_in(device: str, slot: int, ra: float, dec: float) -> None:
    """Store an object in the emulated box as another program would (our raw codec client)."""
    link = await open_link(device.removeprefix("skycommander:"))
    try:
        await CommanderSession(link).send(LoadObject(slot, ra, dec))
    finally:
        await link.close()


async def box_offsets(device: str, ra: float, dec: float) -> tuple[float, float]:
    """The Sky Commander's own ``O`` figures (up, counter-clockwise) to ``ra``/``dec``."""
    link = await open_link(device.removeprefix("skycommander:"))
    try:
        session = CommanderSession(link)
        await session.send(LoadObject.current(ra, dec))
        reply = await session.send(ReadOffsets())
        assert isinstance(reply, OffsetsReply)
        return reply.altitude, reply.azimuth
    finally:
        await link.close()


def test_pushto_agrees_with_the_sky_commanders_own_offsets(
    config: Path, state_dir: Path, box: tuple[str, Path]
) -> None:
    device, _ = box
    result = run(config, state_dir, "pushto", "M 13", "--once", "-d", device)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("M 13: ")
    up, right = figures(result.stdout)
    m13 = lookup("M 13", datetime.now(UTC))
    box_up, box_ccw = asyncio.run(box_offsets(device, m13.ra_hours, m13.dec_deg))
    assert up == pytest.approx(box_up, abs=0.05)  # a second or two later: the sky moved
    assert right == pytest.approx(-box_ccw, abs=0.05)


async def test_pushto_is_live_until_ctrl_c_and_exits_clean(
    config: Path, state_dir: Path, box: tuple[str, Path]
) -> None:
    device, _ = box
    process = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "scopelink",
        "skycommander",
        "pushto",
        "05:35:17",
        "-05:23:28",
        "-d",
        device,
        stdin=asyncio.subprocess.DEVNULL,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
        env={**environment(config), "XDG_STATE_HOME": str(state_dir)},
    )
    assert process.stdout is not None
    lines: list[str] = []
    async with asyncio.timeout(20):
        while len(lines) < 3:
            line = (await process.stdout.readline()).decode()
            assert line, (await process.stderr.read()).decode() if process.stderr else ""
            lines.append(line)
    for line in lines:
        figures(line)
    process.send_signal(signal.SIGINT)
    async with asyncio.timeout(10):
        status = await process.wait()
    stderr = (await process.stderr.read()).decode() if process.stderr else ""
    assert status == 0, stderr
    assert "Traceback" not in stderr


def test_pushto_works_on_any_mount_that_reports_a_position(config: Path, state_dir: Path) -> None:
    result = run(config, state_dir, "pushto", "Vega", "--once", "-d", "sim")
    assert result.returncode == 0, result.stderr
    figures(result.stdout)
    assert result.stdout.startswith("Vega: ")


def test_a_plan_that_is_not_a_small_text_file_is_refused_unread(
    config: Path, state_dir: Path, tmp_path: Path
) -> None:
    result = run(config, state_dir, "upload", "--plan", "/dev/zero", "-d", "skycommander:/dev/null")
    assert result.returncode == 1
    assert "is over 1048576 bytes" in result.stderr
    binary = tmp_path / "plan.bin"
    binary.write_bytes(b"M 31\n\xff\xfe\n")
    result = run(config, state_dir, "upload", "--plan", str(binary), "-d", "skycommander:/dev/null")
    assert result.returncode == 1
    assert "nothing uploaded: cannot read the plan" in result.stderr
    assert "Traceback" not in result.stderr
