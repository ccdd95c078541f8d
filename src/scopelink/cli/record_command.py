"""``scopelink record``: keep every byte of any program's session with a device, with its time.

The command sits between the device and a pseudo-terminal (or a TCP port on 127.0.0.1) that the
program opens instead of the device, relays every byte both ways and writes each transfer to a
recording (JSON lines, ``scopelink.decode.recording``; docs/cli.md, "Record and replay").
"""

from __future__ import annotations

import argparse
import asyncio
import sys
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import IO, TYPE_CHECKING, Final

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.options import parse_host_port
from scopelink.cli.stopping import until_stopped

if TYPE_CHECKING:
    from scopelink.decode import Protocol

__all__ = ["register", "run"]

SKY_TRACKER_STOP_BITS: Final = 2
"""The Sky Tracker's unbuffered port wants 8N2 (specs/NOTES.md); everything else 8N1."""

_EXAMPLES = """\
examples:
  scopelink record --device synscan:/dev/ttyUSB0 session.jsonl
      then point the program at the pty it prints (e.g. scopelink info /dev/pts/7)
  scopelink record --device skytracker:/dev/ttyUSB0 --pty /tmp/scope session.jsonl
  scopelink record --device synscan:tcp://192.168.4.1:11880 --tcp 127.0.0.1:11881 wifi.jsonl
  scopelink decode session.jsonl                      what was said, annotated
  scopelink emulate synscan --replay session.jsonl    a device that answers as recorded
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "record",
        description=(
            "Record a session with a device: relay every byte between the device and a "
            "pseudo-terminal (or TCP port) that a program opens instead, and keep each transfer "
            "with its time in FILE, until Ctrl-C."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("file", metavar="FILE", help="the recording to write (must not exist)")
    parser.add_argument(
        "--device",
        "-d",
        required=True,
        help="the device: synscan:LINK, skytracker:LINK, skycommander:LINK or a bare LINK",
    )
    where = parser.add_mutually_exclusive_group()
    where.add_argument(
        "--pty",
        nargs="?",
        const="",
        metavar="SYMLINK",
        help="the program opens a pseudo-terminal (default), optionally also reachable as SYMLINK",
    )
    where.add_argument(
        "--tcp", metavar="HOST:PORT", help="the program connects over TCP (port 0 picks one)"
    )
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from scopelink.decode import Protocol  # noqa: PLC0415 - only to run
    from scopelink.drivers.open import DeviceOpenError, parse_device  # noqa: PLC0415

    try:
        spec = parse_device(args.device)
    except DeviceOpenError as error:
        raise CommandError(str(error), error.hint) from None
    if spec.kind == "sim":
        raise CommandError(
            "the built-in simulator has no bytes to record",
            "record an emulator instead: scopelink emulate synscan, then --device synscan:PTY",
        )
    path = Path(args.file)
    if path.exists():
        raise CommandError(f"{path} exists", "give a new name: a recording is never overwritten")
    if args.tcp is not None:  # bad input is told before the device or the file is touched
        args.tcp = parse_host_port(args.tcp, "--tcp")
    protocol = Protocol(spec.kind) if spec.kind else None
    stopbits = SKY_TRACKER_STOP_BITS if spec.kind == "skytracker" else 1
    return asyncio.run(_record(args, spec.target, protocol, stopbits, path))


def _create(path: Path) -> IO[str]:
    try:
        return path.open("x", encoding="utf-8")
    except OSError as error:
        raise CommandError(f"cannot write {path}: {error.strerror}") from None


class _Writer:
    """Writes each transfer as it happens (flushed: a crash keeps what was recorded)."""

    def __init__(self, output: IO[str]) -> None:
        self.output = output
        self.start = time.monotonic()
        self.transfers = 0

    def observe(self, from_client: bool, data: bytes) -> None:
        from scopelink.decode import Direction  # noqa: PLC0415 - loaded by run already
        from scopelink.decode.recording import event_line  # noqa: PLC0415

        direction = Direction.PC if from_client else Direction.DEVICE
        self.output.write(event_line(time.monotonic() - self.start, direction, data) + "\n")
        self.output.flush()
        self.transfers += 1


async def _record(
    args: argparse.Namespace,
    target: str,
    protocol: Protocol | None,
    stopbits: int,
    path: Path,
) -> int:
    from scopelink.decode.recording import header_line  # noqa: PLC0415 - only to run
    from scopelink.links import Link, LinkError, open_link, open_pty, serve_tcp  # noqa: PLC0415
    from scopelink.links.relay import relay  # noqa: PLC0415
    from scopelink.servers.hosts import bound_beyond_loopback  # noqa: PLC0415

    try:
        device = await open_link(target, 9600, stopbits=stopbits)
    except LinkError as error:
        raise CommandError(str(error)) from None
    try:
        output = _create(path)  # once the device is open: no empty file for a wrong port
    except CommandError:
        await device.close()
        raise
    started = datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
    output.write(header_line(protocol, device=args.device, started=started) + "\n")
    output.flush()
    writer = _Writer(output)
    busy = asyncio.Lock()
    gone = False
    relaying: asyncio.Task[None] | None = None
    listening = False
    try:
        async with until_stopped() as stop:

            async def serve_client(client: Link) -> None:
                if busy.locked():  # one program at a time: two would interleave on the device
                    return
                async with busy:
                    await relay(client, device, writer.observe)
                if device.closed:  # unplugged, or the peer closed: nothing more to record
                    stop.set()

            if args.tcp is not None:
                host, port = args.tcp
                server = await serve_tcp(serve_client, host=host, port=port)
                if bound_beyond_loopback(host):
                    print(
                        f"warning: the relay listens on {host}: other machines can drive the "
                        "device through it, with no scopelink limits",
                        file=sys.stderr,
                    )
                where = f"tcp://{server.host}:{server.port}"
                closer = server.close
            else:
                pty = await open_pty(args.pty or None)
                where = pty.path
                relaying = asyncio.create_task(serve_client(pty))
                relaying.add_done_callback(lambda _: stop.set())  # the device went, or a fault
                closer = pty.close
            listening = True
            print(f"recording {args.device} to {args.file}: connect the program to {where}")
            print("Ctrl-C ends the recording.", flush=True)
            await stop.wait()
            gone = device.closed
            await closer()
            if relaying is not None and relaying.done() and not relaying.cancelled():
                relaying.result()  # a fault of the relay itself: reported below
    except (LinkError, OSError) as error:
        raise CommandError(str(error)) from None
    finally:
        if relaying is not None:
            relaying.cancel()
        await device.close()
        output.close()
        if not listening:  # it never started: no header-only file to block the retry
            await asyncio.to_thread(path.unlink, missing_ok=True)
    note = " (the device went away)" if gone else ""
    print(f"recorded {writer.transfers} transfers to {args.file}{note}", file=sys.stderr)
    return 1 if gone else 0
