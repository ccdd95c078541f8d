"""``scopelink decode``: the real console script, files and stdin, carets, JSON, the README."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from scopelink.cli.main import main

REPO = Path(__file__).resolve().parents[2]
_SCRIPT = Path(sys.executable).with_name("scopelink")


def _scopelink(*args: str, stdin: bytes = b"") -> subprocess.CompletedProcess[str]:
    command = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "scopelink"]
    return subprocess.run(
        [*command, *args],
        input=stdin.decode("latin-1"),
        capture_output=True,
        text=True,
        timeout=30,
        check=False,
    )


def test_console_script_annotates_the_issue_example() -> None:
    result = _scopelink("decode", "e", "34AB0500,12CE0500#")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == [
        "     0  ->  e                   get precise RA/Dec",
        "     1  <-  34AB0500,12CE0500#  RA 4h 56m 15.5s, Dec +26.44°",
    ]


def test_console_script_error_has_a_caret_and_status_1() -> None:
    result = _scopelink("decode", "e", "34AB05G0,12CE0500#")
    assert result.returncode == 1
    lines = result.stdout.splitlines()
    assert "error: reply to 'get precise RA/Dec' does not fit" in lines[1]
    stream, caret = lines[2], lines[3]
    assert stream.strip() == "e34AB05G0,12CE0500#"
    assert stream[caret.index("^")] == "G"
    assert "1 error in the trace" in result.stderr


def test_console_script_reads_an_indi_log_from_stdin() -> None:
    log = b"[DEBUG] CMD <V>\n[INFO] something else\n[DEBUG] RES <042507#>\n"
    result = _scopelink("decode", "--file", "-", stdin=log)
    assert result.returncode == 0, result.stderr
    assert "version 4.37.07" in result.stdout


def test_hex_mode_caret_names_the_byte(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", "--hex", "58 56", "30 34 32 35 30 37 23"]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert "error: unknown command byte 0x58 ('X')" in lines[0]
    assert lines[1].strip() == "58 56 30 34 32 35 30 37 23"
    assert lines[2].strip() == "^ byte 0"
    assert lines[1].index("58") == lines[2].index("^")


def test_truncated_reply_fails(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", "--protocol", "skycommander", r"\r 12.345"]) == 1
    assert "incomplete reply to 'CR: read position': 7 of 16 bytes" in capsys.readouterr().out


def test_file_with_tags_and_raw_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    tagged = tmp_path / "trace.txt"
    tagged.write_bytes(b"PC: Q\nST: A\nPC: L99 12.345 +67.890\\r\nSC: A\nPC: q\nPC: G\n")
    assert main(["decode", "--protocol", "skytracker", "--file", str(tagged)]) == 0
    tagged_out = capsys.readouterr().out
    raw = tmp_path / "trace.bin"
    raw.write_bytes(b"QAL99 12.345 +67.890\rAqG")
    assert main(["decode", "--protocol", "skytracker", "--raw", "--file", str(raw)]) == 0
    assert capsys.readouterr().out == tagged_out
    assert "[SC] L99: load RA 12h 20m 42s, Dec +67.890° as current object" in tagged_out


def test_json_lines(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", "--json", "T\\0", "#", "M", "#"]) == 0
    objects = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [(o["offset"], o["kind"], o["message"], o["answers"]) for o in objects] == [
        (0, "command", "SetTrackingMode", None),
        (2, "reply", "Ack", 0),
        (3, "command", "CancelGoto", None),
        (4, "reply", "Ack", 3),
    ]
    assert objects[0]["hex"] == "54 00"
    assert objects[0]["text"] == "T\\0"


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["decode"], "nothing to decode"),
        (["decode", "--file", "x", "e"], "not both"),
        (["decode", "--raw", "e"], "--raw reads a file"),
        (["decode", "--file", "/nonexistent/trace"], "cannot read /nonexistent/trace"),
        (["decode", "e\\q"], "cannot read the trace: unknown escape"),
    ],
)
def test_user_errors_are_one_clear_message(
    args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(args) == 1
    assert message in capsys.readouterr().err


def test_bad_escape_shows_where(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["decode", "> e\\q"]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err[1].strip() == "> e\\\\q"
    assert err[1].index("\\") == err[2].index("^")


def test_readme_quick_start_examples_run() -> None:
    readme = (REPO / "README.md").read_text(encoding="utf-8")
    section = readme.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    blocks = [part.split("```", 1)[0] for part in section.split("```sh\n")[1:]]
    examples = [
        line
        for block in blocks
        for line in block.splitlines()
        if re.search(r"\bscopelink decode\b", line)
    ]
    assert len(examples) >= 4
    environment = {**os.environ, "PATH": f"{_SCRIPT.parent}{os.pathsep}{os.environ['PATH']}"}
    for example in examples:
        result = subprocess.run(
            ["bash", "-c", example],
            env=environment,
            capture_output=True,
            text=True,
            timeout=30,
            check=False,
        )
        assert result.returncode == 0, f"{example}\n{result.stdout}{result.stderr}"
        assert "->" in result.stdout
