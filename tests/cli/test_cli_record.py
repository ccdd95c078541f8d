"""`scopelink record`, `decode FILE` and `emulate synscan --replay FILE` as a user runs them:
a real emulator behind the recorder's pty, scopelink's own driver in front of it."""

from __future__ import annotations

import asyncio
import json
import re
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

from scopelink.astro import Site
from scopelink.decode import Direction, annotate
from scopelink.decode.recording import read_recording
from scopelink.drivers.synscan import SynScanMount
from scopelink.links import Link, open_serial, open_tcp
from scopelink.servers.replay import ReplayDevice, replay_to_driver
from scopelink.servers.synscan import SynScanConfig, SynScanEmulator
from scopelink.sim import PRESETS, SimClock, SimulatedMount
from tests.support.cli import read_line_matching, scopelink_here, start_scopelink

SITE = Site(40.4, -3.7)
DOCS = Path(__file__).parents[2] / "docs" / "cli.md"


async def asked(link: Link, command: bytes, size: int) -> bytes:
    """Send ``command``; the ``size`` bytes answered (within 5 s)."""
    await link.write(command)
    async with asyncio.timeout(5):
        return await link.read_exactly(size)


async def test_record_decode_replay_and_the_regression_test(tmp_path: Path, config: Path) -> None:
    recording = tmp_path / "session.jsonl"
    mount = SimulatedMount(PRESETS["eq6"], site=SITE, clock=SimClock(rate=1.0))
    async with SynScanEmulator(mount, SynScanConfig(model=0), wire=None) as emulator:
        device = await emulator.on_pty()
        recorder = await start_scopelink(
            config, "record", "--device", f"synscan:{device}", str(recording)
        )
        line = await read_line_matching(recorder.stdout, "connect the program to", recorder.stderr)
        client_pty = line.rsplit(" ", 1)[1].strip()
        driver = SynScanMount(client_pty, site=SITE)
        await driver.connect()  # any program: here scopelink's own driver
        identity = driver.identity
        await driver.disconnect()
        recorder.send_signal(signal.SIGINT)
        async with asyncio.timeout(10):
            assert await recorder.wait() == 0
        assert recorder.stderr is not None
        assert re.search(r"recorded \d+ transfers", (await recorder.stderr.read()).decode())

    # The file: a versioned header, then every transfer with its time and direction.
    lines = recording.read_text().splitlines()
    header = json.loads(lines[0])
    assert header["scopelink_recording"] == 1
    assert header["protocol"] == "synscan"
    first = json.loads(lines[1])
    assert first["dir"] == "->"
    assert first["data"].startswith("K")
    loaded = read_recording(recording.read_bytes())
    times = [transfer.t for transfer in loaded.transfers]
    assert times == sorted(times)
    assert times[0] > 0
    assert {t.direction for t in loaded.transfers} == {Direction.PC, Direction.DEVICE}
    assert not any(a.is_error for a in annotate(loaded.chunks()))

    # `decode FILE`: the recording's own protocol, each line annotated.
    status, out, _ = scopelink_here(config, "decode", str(recording))
    assert status == 0
    assert "get hand control version" in out
    assert "version 4.39.05" in out

    # The regression test as docs/cli.md shows it, run by pytest beside the recording.
    snippet = re.search(r"```python\n(.*?replay_to_driver.*?)```", DOCS.read_text(), re.S)
    assert snippet is not None
    (tmp_path / "test_recorded.py").write_text(textwrap.dedent(snippet[1]))
    (tmp_path / "pytest.ini").write_text("[pytest]\nasyncio_mode = auto\n")
    run = await asyncio.to_thread(
        subprocess.run,
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_recorded.py"],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stdout
    assert "1 passed" in run.stdout
    # The same, here: the driver against the recording, no divergence, same identity.
    result = await replay_to_driver(recording, site=SITE)
    assert result.divergences == ()
    assert result.identity.model == identity.model == "EQ6 GOTO"
    assert result.identity.firmware == identity.firmware
    assert result.exchanges_played == result.exchanges_recorded

    # A divergence is reported with the line and the byte, not answered; the replay resumes.
    device_replay = ReplayDevice(loaded)
    async with device_replay, await open_serial(await device_replay.on_pty()) as link:
        await link.write(b"Kz")  # recorded: K\x80
        await link.write(first["data"].replace("\\x80", "\x80").encode("latin-1"))
        async with asyncio.timeout(5):
            assert await link.read_exactly(2) == b"\x80#"
    (divergence,) = device_replay.divergences
    assert (divergence.line, divergence.offset, divergence.received) == (2, 1, b"z")
    assert "divergence at line 2 (exchange 1, byte 1): expected '\\x80', received 'z'" in (
        divergence.describe()
    )


def test_replay_refuses_a_recording_of_another_device(tmp_path: Path, config: Path) -> None:
    recording = tmp_path / "tracker.jsonl"
    recording.write_text(
        '{"scopelink_recording": 1, "protocol": "skytracker"}\n'
        '{"t": 0.5, "dir": "->", "data": "V"}\n{"t": 0.51, "dir": "<-", "data": "v4.0    "}\n'
    )
    status, _, err = scopelink_here(config, "emulate", "synscan", "--replay", str(recording))
    assert status == 1
    assert "recorded from a skytracker device" in err
    assert f"scopelink emulate skytracker --replay {recording}" in err
    broken = tmp_path / "broken.jsonl"
    broken.write_text('{"scopelink_recording": 1, "protocol": "synscan"}\n{"t": 1, "dir": "=>"}\n')
    status, _, err = scopelink_here(config, "decode", "--file", str(broken))
    assert status == 1
    assert "line 2: 'dir' must be '->' or '<-'" in err
    status, _, err = scopelink_here(config, "record", "--device", "sim", str(broken))
    assert status == 1
    assert "no bytes to record" in err


async def test_emulate_replay_answers_and_reports_divergences_on_stderr(
    tmp_path: Path, config: Path
) -> None:
    recording = tmp_path / "session.jsonl"
    recording.write_text(
        '{"scopelink_recording": 1, "protocol": "synscan"}\n'
        '{"t": 0.1, "dir": "->", "data": "V"}\n{"t": 0.11, "dir": "<-", "data": "042705#"}\n'
        '{"t": 0.2, "dir": "->", "data": "J"}\n{"t": 0.21, "dir": "<-", "data": "\\\\x01#"}\n'
    )
    emulator = await start_scopelink(
        config, "emulate", "synscan", "--replay", str(recording), "--tcp", "127.0.0.1:0"
    )
    try:
        line = await read_line_matching(emulator.stdout, r"listening on", emulator.stderr)
        port = int(line.rsplit(":", 1)[1])
        async with await open_tcp("127.0.0.1", port) as link:
            await link.write(b"e")  # not recorded here: reported, not answered
            assert await asked(link, b"V", 7) == b"042705#"
            assert await asked(link, b"J", 2) == b"\x01#"
    finally:
        emulator.send_signal(signal.SIGTERM)
        async with asyncio.timeout(10):
            assert await emulator.wait() == 0
    assert emulator.stderr is not None
    err = (await emulator.stderr.read()).decode()
    assert "replaying 2 exchanges from" in err
    assert "replay: divergence at line 2 (exchange 1, byte 0): expected 'V', received 'e'" in err


def test_a_record_that_cannot_start_leaves_no_file(tmp_path: Path, config: Path) -> None:
    """Bad input costs one line and nothing else: no header-only file blocks the retry."""
    recording = tmp_path / "session.jsonl"
    for where, said in (
        (("--tcp", "abc"), "bad --tcp 'abc'"),
        (("--tcp", "127.0.0.1:99999"), "bad --tcp"),
        (("--tcp", "203.0.113.5:0"), "cannot open tcp server 203.0.113.5:0"),
        (("--pty", str(tmp_path / "absent" / "link")), "cannot open pty"),
    ):
        status, _, err = scopelink_here(
            config, "record", "--device", "synscan:loop://", *where, str(recording)
        )
        assert (status, err.count("\n")) in ((1, 1), (1, 2)), err
        assert said in err
        assert "Traceback" not in err
        assert not recording.exists(), where


async def test_a_command_cut_short_and_sent_again_is_answered(tmp_path: Path) -> None:
    """A client that times out mid-command and sends it again from the start ("K" then "Ka",
    on the wire "KKa") gets the recorded answer: the byte that broke the match may begin it."""
    recording = tmp_path / "retry.jsonl"
    recording.write_text(
        '{"scopelink_recording": 1, "protocol": "synscan"}\n'
        '{"t": 0.1, "dir": "->", "data": "Ka"}\n{"t": 0.2, "dir": "<-", "data": "a#"}\n'
        '{"t": 0.3, "dir": "->", "data": "V"}\n{"t": 0.4, "dir": "<-", "data": "042507#"}\n'
    )
    replay = ReplayDevice(read_recording(recording.read_bytes()))
    async with replay, await open_serial(await replay.on_pty()) as link:
        assert await asked(link, b"KKa", 2) == b"a#"
        assert await asked(link, b"V", 7) == b"042507#"
    (divergence,) = replay.divergences
    assert (divergence.line, divergence.offset, divergence.received) == (2, 1, b"K")
