"""scopelink.testing.EmulatorHandle: an emulator on its own thread, its address, state and log,
a clean stop (no thread, task, port or pty left), its options and their documented defaults."""

from __future__ import annotations

import socket
import subprocess
import sys
import threading
from dataclasses import fields
from datetime import datetime, timedelta
from pathlib import Path

import pytest
import serial

from scopelink.links import open_tcp
from scopelink.mount import TrackingMode
from scopelink.protocol.skytracker import TrackerMode
from scopelink.protocol.synscan import GetRaDec, GetVersion, SetTrackingMode, Tracking
from scopelink.servers.synscan import DEFAULT_FIRMWARE
from scopelink.testing import EmulatorHandle, EmulatorSpec, EmulatorSpecError
from scopelink.testing.handle import (
    CALL_TIMEOUT_S,
    START_TIMEOUT_S,
    STOP_TIMEOUT_S,
    TASK_GRACE_S,
)
from scopelink.testing.options import DEFAULT_MODELS


def _emulator_threads() -> list[threading.Thread]:
    return [thread for thread in threading.enumerate() if thread.name.startswith("scopelink ")]


async def test_from_asyncio_it_serves_logs_and_stops_without_leaving_anything() -> None:
    async with EmulatorHandle(device="synscan", clock_rate=0, pacing=False) as emulator:
        assert len(_emulator_threads()) == 1
        assert emulator.url == f"tcp://127.0.0.1:{emulator.port}"
        assert emulator.device_string == f"synscan:{emulator.url}"
        async with await open_tcp(emulator.host, emulator.port) as link:
            await link.write(b"eV")  # two commands in one write, as the log shows them
            assert len(await link.read_exactly(18 + 7)) == 25
            before = emulator.state()  # read from inside a running loop: no deadlock
            emulator.advance(600.0)
            after = emulator.state()
            assert after.read_at - before.read_at == timedelta(seconds=600)
            assert emulator.altaz == (before.alt_deg, before.az_deg)  # not tracking: it stood
            assert emulator.position != (before.ra_j2000_hours, before.dec_j2000_deg)
            await link.write(b"T\x02")  # track: the mount layer's meridian watch starts
            assert await link.read_exactly(1) == b"#"
            assert emulator.tracking is TrackingMode.SIDEREAL
        assert emulator.commands() == [
            GetRaDec(precise=True),
            GetVersion(),
            SetTrackingMode(Tracking.EQUATORIAL),
        ]
        assert [chunk.elapsed_s for chunk in emulator.chunks] == [0.0, 600.0]  # stepped
        port = emulator.port
    assert not emulator.running
    assert _emulator_threads() == []
    assert emulator.stray_tasks == []
    with pytest.raises(ConnectionRefusedError):
        socket.create_connection(("127.0.0.1", port), timeout=2).close()
    with pytest.raises(RuntimeError, match="not running"):
        emulator.state()


def test_a_sky_tracker_on_a_pty_with_a_fault_added_while_it_runs() -> None:
    with EmulatorHandle(EmulatorSpec(device="skytracker", transport="pty")) as tracker:
        path = tracker.path
        assert tracker.info["pty"] == path
        tracker.inject("V:drop")
        with serial.Serial(path, 9600, timeout=0.3) as port:
            port.write(b"T")
            port.write(b"V")
            assert port.read(8) == b""
            port.timeout = 2
            port.write(b"V")
            assert port.read(8) == b"v4.0    "
        assert tracker.mode is TrackerMode.TRACK
        assert tracker.received == b"TVV"
        assert [fired.command for fired in tracker.faults.fired] == ["V"]
        with pytest.raises(TypeError, match="received"):
            tracker.commands()
        scratch = tracker.data_dir
        assert scratch.is_dir()
    assert not Path(path).exists()  # the pty went with it
    assert not scratch.exists()  # and its temporary memory
    assert _emulator_threads() == []


def test_a_failed_start_raises_in_the_caller_and_leaves_no_thread(tmp_path: Path) -> None:
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    handle = EmulatorHandle(device="skycommander", data_dir=blocker / "below")
    with pytest.raises(NotADirectoryError):
        handle.start()
    assert not handle.running
    assert _emulator_threads() == []


def test_names_are_read_in_any_case_and_one_fault_rule_needs_no_list() -> None:
    spec = EmulatorSpec(device="SynScan", transport="PTY", model="az-gti", faults="e:drop")
    assert (spec.device, spec.transport, spec.model_name) == ("synscan", "pty", "az-gti")
    assert [rule.command for rule in spec.make_faults().faults] == ["e"]


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"device": "skytracker", "model": "EQ6"}, "alt-azimuth telescope only, not the EQ6"),
        ({"device": "skycommander", "model": "heq5"}, "not the HEQ5"),
        ({"device": "skytracker", "firmware": "4.39.05"}, "firmware is the SynScan"),
        ({"device": "nexstar"}, "device 'nexstar' is not one of synscan, skytracker"),
        ({"transport": "usb"}, "transport 'usb' is not one of tcp, pty"),
        ({"model": "EQ8"}, "model 'EQ8' is not one of EQ6, HEQ5"),
        ({"model": "Sky Tracker"}, "does not drive the Sky Tracker: give model_code"),
        ({"firmware": "4.39"}, "firmware '4.39' is not a version like 4.39.05"),
        ({"clock_rate": -1}, "clock rate -1 must be a finite number >= 0"),
        ({"faults": ["e:explode"]}, "explode"),
        ({"site": (95.0, 0.0)}, "latitude_deg must be in [-90, 90]"),
        ({"site": "Madrid"}, "site 'Madrid' is not LAT,LON"),
        ({"pacing": "no"}, "pacing is True or False, not 'no'"),
        ({"start": datetime(2026, 1, 1)}, "must carry a time zone"),
        ({"model_code": 256}, "model code 256 must be a byte"),
    ],
)
def test_nonsense_is_refused_in_one_line(options: dict[str, object], message: str) -> None:
    with pytest.raises(EmulatorSpecError) as refusal:
        EmulatorSpec(**options)  # type: ignore[arg-type]
    assert message in str(refusal.value)
    assert "\n" not in str(refusal.value)


def test_the_documented_defaults_are_the_codes() -> None:
    page = (Path(__file__).resolve().parents[2] / "docs" / "testing-with-scopelink.md").read_text()
    rows = {
        cells[0].strip("` "): cells[-1]
        for line in page.splitlines()
        if line.startswith("| `") and len(cells := line.strip("|").split("|")) == 3
    }
    spec = EmulatorSpec()
    firmware = DEFAULT_FIRMWARE
    expected = {
        "transport": f'`"{spec.transport}"`',
        "model": f'`"{DEFAULT_MODELS["synscan"]}"` (SynScan), `"{DEFAULT_MODELS["skytracker"]}"`',
        "firmware": f'`"{firmware.major}.{firmware.minor:02}.{firmware.patch:02}"`',
        "aligned": f"`{spec.aligned}`",
        "site": f'`"{spec.site}"`',
        "clock_rate": f"`{spec.clock_rate}`",
        "start": spec.start.strftime("%Y-%m-%d %H:%M UTC"),
        "pacing": f"`{spec.pacing}`",
    }
    for option, default in expected.items():
        assert default in rows[option], option
    assert set(rows) >= {field.name for field in fields(EmulatorSpec)} - {"device"}
    assert DEFAULT_MODELS["skycommander"] == DEFAULT_MODELS["skytracker"]
    assert f"waits at most {START_TIMEOUT_S:g} s" in page
    assert f"`close()` {STOP_TIMEOUT_S:g} s" in page
    assert f"`handle.TASK_GRACE_S` ({TASK_GRACE_S:g} s)" in page
    assert f"`handle.CALL_TIMEOUT_S` ({CALL_TIMEOUT_S:g} s)" in page


def test_loading_the_plugin_imports_nothing_heavy() -> None:
    """pytest imports the plugin at every start, in every project where scopelink is installed."""
    script = "import sys, scopelink.testing.plugin; print(*sorted(m for m in sys.modules))"
    loaded = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    ).stdout
    ours = [name for name in loaded.split() if name.split(".")[0] == "scopelink"]
    assert ours == ["scopelink", "scopelink.testing", "scopelink.testing.plugin"]
    assert "numpy" not in loaded.split()
