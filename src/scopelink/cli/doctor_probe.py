"""What answers on an open line, asked with read-only commands only (``scopelink doctor``).

The questions, in this order, each asked only while nothing has been recognised yet:

1. ``V`` (read the version): a SynScan hand control answers 6 hex digits + ``#`` (3 binary bytes
   + ``#`` on old firmware), a Celestron NexStar hand control 2 binary bytes + ``#``, a Sky Tracker
   8 characters (``v4.0    ``). A SynScan hand control is then asked ``m`` (model) and ``J``
   (aligned?); a NexStar ``m``; a Sky Tracker ``R`` (its status byte) and then, over its bus,
   ``Q`` (request), CR (the Sky Commander's position) and ``q`` (release).
2. CR alone: a Sky Commander alone on its port answers its position (16 bytes).
3. ``:e1`` CR (motor board version): a SynScan motor controller answers ``=``...CR; a hand control
   in PC-Direct mode passes the motor controller's answer through.

None of these moves anything or changes a setting; ``K`` (SynScan's echo) is not sent, since the
Sky Tracker reads it as "set guide speed".
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass, field
from typing import Final

from scopelink.decode import escape_bytes
from scopelink.links import Link
from scopelink.protocol import skytracker, synscan

__all__ = ["FIRST_BYTE_WAIT_S", "QUIET_S", "Finding", "probe"]

FIRST_BYTE_WAIT_S: Final = 1.0
"""How long each question waits for a first byte (real devices answer within ~100 ms)."""
QUIET_S: Final = 0.15
"""An answer ends when the line has been quiet this long."""

_MOTOR_VERSION: Final = b":e1\r"
_COMMANDER_POSITION: Final = b"\r"


@dataclass(slots=True)
class Finding:
    """What is on a port: ``kind`` for scripts, ``what`` and ``advice`` for people."""

    kind: str
    what: str
    advice: str
    usable: bool = False
    """Whether scopelink can drive what answered, as it is now."""
    device: str | None = None
    """The DEVICE string to give scopelink for it."""
    details: dict[str, object] = field(default_factory=dict)


async def ask(link: Link, question: bytes, wait_s: float = FIRST_BYTE_WAIT_S) -> bytes:
    """Send ``question``; what came back until the line went quiet (b"" if nothing)."""
    await link.write(question)
    try:
        async with asyncio.timeout(wait_s):
            first = await link.read()
    except TimeoutError:
        return b""
    return first + await link.drain_input(quiet_seconds=QUIET_S, max_seconds=1.0)


async def probe(link: Link, port: str, wait_s: float = FIRST_BYTE_WAIT_S) -> Finding:
    """Ask the read-only questions in turn and say what answered on ``link`` (``port``)."""
    unprompted = await link.drain_input(quiet_seconds=0.1, max_seconds=0.5)
    version = await ask(link, b"V", wait_s)
    if version:
        found = await _after_version(link, port, version, wait_s)
        if found is not None:
            return found
        return _unrecognised(port, version, "V")
    commander = await ask(link, _COMMANDER_POSITION, wait_s)
    if commander:
        return _sky_commander_alone(port, commander)
    motor = await ask(link, _MOTOR_VERSION, wait_s)
    if motor:
        return _motor_controller(port, motor)
    if unprompted:
        return _unrecognised(port, unprompted, None)
    return Finding(
        "nothing",
        "nothing answered (no reply to V, to CR or to :e1)",
        "check that the hand control (or Sky Tracker) is switched on and past its start-up "
        "screens, that the cable is in its PC port (not the autoguider or motor port), and for "
        "a home-made cable that TX and RX are not swapped",
    )


async def _after_version(link: Link, port: str, reply: bytes, wait_s: float) -> Finding | None:
    try:
        version = synscan.parse_reply(synscan.GetVersion(), reply)
    except synscan.ReplyError:
        version = None
    if isinstance(version, synscan.Version):
        if version.dialect is synscan.VersionDialect.NEXSTAR_BINARY:
            return await _nexstar(link, port, version, wait_s)
        return await _synscan(link, port, version, wait_s)
    if len(reply) == skytracker.VersionReply.size and reply.isascii() and reply[:1] == b"v":
        return await _sky_tracker(link, port, reply.decode("ascii"), wait_s)
    return None


async def _synscan(link: Link, port: str, version: synscan.Version, wait_s: float) -> Finding:
    firmware = f"{version.major:02d}.{version.minor:02d}.{version.patch or 0:02d}"
    details: dict[str, object] = {"firmware": firmware}
    parts = [f"a SynScan hand control, firmware {firmware}"]
    model = _parsed(synscan.GetModel(), await ask(link, b"m", wait_s))
    if isinstance(model, synscan.Model):
        details |= {"model": model.name, "model_code": model.code}
        parts.append(f"model {model.name} (code {model.code})")
    aligned = _parsed(synscan.IsAligned(), await ask(link, b"J", wait_s))
    advice = f"use --device synscan:{port} (e.g. scopelink info synscan:{port})"
    if isinstance(aligned, synscan.Aligned):
        details["aligned"] = aligned.aligned
        parts.append("aligned" if aligned.aligned else "NOT aligned")
        if not aligned.aligned:
            advice = "finish the star alignment on the hand control (gotos need it), then " + advice
    parts.append("not in PC-Direct mode (it answers the hand-control protocol, as scopelink needs)")
    return Finding("synscan", ", ".join(parts), advice, True, f"synscan:{port}", details)


async def _nexstar(link: Link, port: str, version: synscan.Version, wait_s: float) -> Finding:
    details: dict[str, object] = {"firmware": f"{version.major}.{version.minor}"}
    model = await ask(link, b"m", wait_s)
    if len(model) == 2 and model[1:] == b"#":
        details["model_code"] = model[0]
    return Finding(
        "nexstar",
        f"a Celestron NexStar hand control, firmware {version.major}.{version.minor} "
        "(its version reply has two numbers, SynScan's three)",
        "scopelink drives Sky-Watcher SynScan hand controls and Sky Trackers, not Celestron "
        "mounts: use a NexStar driver (INDI's Celestron NexStar, ASCOM's Celestron driver)",
        details=details,
    )


async def _sky_tracker(link: Link, port: str, version: str, wait_s: float) -> Finding:
    details: dict[str, object] = {"firmware": version.strip()}
    status = await ask(link, b"R", wait_s)
    goto = False
    if len(status) == skytracker.StatusReply.size:
        flags = status[0]
        goto = bool(flags & skytracker.ModeFlag.GOTO)
        details["status_byte"] = flags
    commander = await _commander_on_bus(link, wait_s)
    details["sky_commander"] = commander
    device = f"skytracker:{port}"
    what = f"a Sky Tracker, firmware {version.strip()!r}"
    if commander is True:
        return Finding(
            "skytracker",
            what + ", with its Sky Commander answering on the bus",
            f"use --device {device}",
            True,
            device,
            details,
        )
    if commander is None:
        why = "a GOTO is running" if goto else "the Sky Tracker refused the bus"
        return Finding(
            "skytracker",
            what + f"; whether a Sky Commander is on its bus is unknown ({why})",
            f"use --device {device}; run 'scopelink doctor' again once the GOTO has ended",
            True,
            device,
            details,
        )
    return Finding(
        "skytracker",
        what + ", with NO Sky Commander answering on its bus",
        "connect the Sky Commander to the Sky Tracker and switch it on: positions and gotos "
        f"come from it (scopelink can still drive the motors with --device {device})",
        True,
        device,
        details,
    )


async def _commander_on_bus(link: Link, wait_s: float) -> bool | None:
    """Whether a Sky Commander answers behind the Sky Tracker: None when the bus is refused."""
    grant = await ask(link, b"Q", wait_s)
    if grant != b"A":
        if grant != b"\0":  # a grant that came late or garbled must not keep the bus held
            await link.write(b"q")
        return None
    try:
        position = await ask(link, _COMMANDER_POSITION, wait_s)
    finally:
        await link.write(b"q")
    return _commander_position(position) is not None


def _commander_position(reply: bytes) -> skytracker.PositionReply | None:
    if len(reply) != skytracker.PositionReply.size:
        return None
    try:
        return skytracker.PositionReply.decode(reply)
    except ValueError:
        return None


def _sky_commander_alone(port: str, reply: bytes) -> Finding:
    position = _commander_position(reply)
    if position is None:
        return _unrecognised(port, reply, "CR")
    device = f"skycommander:{port}"
    return Finding(
        "skycommander",
        f"a Sky Commander alone on its port (pointing at RA {position.ra_hours:.3f} h, Dec "
        f"{position.dec_degrees:+.3f}°): push-to, nothing moves",
        f"use --device {device} (reads, syncs, its object memory; 'scopelink skycommander')",
        True,
        device,
        {"ra_hours": position.ra_hours, "dec_deg": position.dec_degrees},
    )


def _motor_controller(port: str, reply: bytes) -> Finding:
    if not (reply[:1] in (b"=", b"!") and reply.endswith(b"\r")):
        return _unrecognised(port, reply, ":e1")
    return Finding(
        "synscan-motor-controller",
        "a SynScan motor controller speaking its own ':' protocol (answered "
        f"'{escape_bytes(reply)}'): the hand control is not in between, or is in PC-Direct mode",
        "scopelink speaks the hand control's protocol: connect the cable to the hand control's "
        "PC port, or leave PC-Direct mode (switch the hand control off and on); a direct "
        "(EQDIR/USB) connection to the mount needs an EQMOD driver instead",
        details={"reply": escape_bytes(reply)},
    )


def _unrecognised(port: str, reply: bytes, question: str | None) -> Finding:
    """Bytes that fit no device: mostly non-text is a wrong line speed; text is another device."""
    garbled = sum(not (0x20 <= byte < 0x7F or byte in b"\r\n#\0") for byte in reply)
    asked = f"to {question}" if question else "unprompted"
    shown = reply[:24].hex(" ")
    details: dict[str, object] = {"reply_hex": reply.hex(" ")}
    if garbled * 2 >= len(reply):
        return Finding(
            "garbage",
            f"something answers {asked}, but with bytes that fit no protocol ({shown}): "
            "the line speed is probably wrong",
            "hand controls, Sky Trackers and Sky Commanders talk at 9600 baud, 8N1: check any "
            "serial-to-network bridge or adapter setting; is it another device (GPS, Arduino)?",
            details=details,
        )
    return Finding(
        "unrecognised",
        f"something answers {asked}, but as no SynScan, Sky Tracker or Sky Commander would "
        f"('{escape_bytes(reply[:40])}')",
        "is it another device on this port? 'scopelink ports' lists the ports",
        details=details,
    )


def _parsed(command: synscan.AnyCommand, reply: bytes) -> synscan.AnyReply | None:
    try:
        return synscan.parse_reply(command, reply)
    except synscan.ReplyError:
        return None
