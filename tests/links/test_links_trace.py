"""The DEBUG hex trace: one line per transfer, both directions, once per link."""

import logging

import pytest

from scopelink.links import memory_pair, paced
from scopelink.links.trace import escape_text

TRACE = "scopelink.links.trace"


def trace_lines(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [record.getMessage() for record in caplog.records if record.name == TRACE]


async def test_both_directions_are_traced_in_hex_and_text(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=TRACE)
    pc, mount = memory_pair(("pc", "mount"))
    await pc.write(b":e1\r")
    await mount.read()
    await mount.write(b"\x00\xff#")
    await pc.read()
    assert trace_lines(caplog) == [
        'pc --> 4 bytes: 3a 65 31 0d | ":e1\\r"',
        'mount <-- 4 bytes: 3a 65 31 0d | ":e1\\r"',
        'mount --> 3 bytes: 00 ff 23 | "\\x00\\xff#"',
        'pc <-- 3 bytes: 00 ff 23 | "\\x00\\xff#"',
    ]
    assert all(record.levelno == logging.DEBUG for record in caplog.records)


async def test_a_paced_link_traces_each_transfer_once(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger=TRACE)
    pc, mount = memory_pair(("pc", "mount"))
    line = paced(pc, 96000, 11)
    await line.write(b"Kx")
    await mount.write(b"x#")
    await line.read()
    assert trace_lines(caplog) == [
        'pc --> 2 bytes: 4b 78 | "Kx"',
        'mount --> 2 bytes: 78 23 | "x#"',
        'pc <-- 2 bytes: 78 23 | "x#"',
    ]


async def test_nothing_is_traced_above_debug(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger=TRACE)
    pc, mount = memory_pair()
    await pc.write(b"hello")
    await mount.read()
    assert trace_lines(caplog) == []


def test_escape_text_keeps_printables_and_escapes_the_rest() -> None:
    assert escape_text(b'R\t\n"\\\x7f\x80 ~') == 'R\\t\\n\\"\\\\\\x7f\\x80 ~'
