"""``scopelink emulate ... --ready-json``: one JSON line on stdout once listening, then nothing."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import serial


def _start(*arguments: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "scopelink", "emulate", *arguments, "--ready-json", "--no-pacing"],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )


def _stop(process: subprocess.Popen[str]) -> str:
    process.send_signal(signal.SIGTERM)
    rest, _ = process.communicate(timeout=10)
    assert process.returncode == 0
    return rest


def test_ready_json_says_where_and_what_over_tcp_and_a_pty(tmp_path: Path) -> None:
    synscan = _start("synscan", "--tcp", "127.0.0.1:0", "--mount", "az-gti", "--firmware", "3.39.5")
    commander = _start("skycommander", "--data-dir", str(tmp_path))
    try:
        assert synscan.stdout is not None
        assert commander.stdout is not None
        over_tcp = json.loads(synscan.stdout.readline())
        on_pty = json.loads(commander.stdout.readline())
        host, port = over_tcp["tcp"].rsplit(":", 1)
        assert over_tcp == {
            "protocol": "synscan",
            "tcp": f"127.0.0.1:{port}",
            "device": f"synscan:tcp://127.0.0.1:{port}",
            "model": "AZ-GTi",
            "model_code": 165,
            "firmware": "3.39.05",
            "pid": synscan.pid,
        }
        assert on_pty["pty"].startswith("/dev/pts/")
        assert on_pty == {
            "protocol": "skycommander",
            "pty": on_pty["pty"],
            "device": f"skycommander:{on_pty['pty']}",
            "model": "Sky Commander",
            "pid": commander.pid,
        }
        with serial.serial_for_url(f"socket://{host}:{port}", timeout=5) as port_:
            port_.write(b"V")
            assert port_.read(7) == b"032705#"  # the ready line came once it was listening
        with serial.Serial(on_pty["pty"], 9600, timeout=5) as line:
            line.write(b"\r")
            assert len(line.read(16)) == 16
    finally:
        rest = _stop(synscan), _stop(commander)
    assert rest == ("", "")  # nothing else on stdout
