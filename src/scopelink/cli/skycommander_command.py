"""``scopelink skycommander``: the Sky Commander's memory (``L00``-``L58``) and a push-to view.

``slots`` shows what scopelink last wrote (a local mirror: the box cannot be read back),
``upload`` stores objects by name, coordinates or a plan file, ``clear`` overwrites the slots
scopelink wrote with a harmless placeholder (or only forgets them), and ``pushto`` shows live how
far to push the scope on each axis. Decisions: ``docs/drivers-skytracker.md``, "Sky Commander
memory and push-to"; usage: ``docs/cli.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import sys
from collections.abc import Awaitable, Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Final

from scopelink.cli.commands import CommandParsers
from scopelink.cli.errors import CommandError
from scopelink.cli.options import add_device_arguments
from scopelink.cli.targets import accept_negative_values

if TYPE_CHECKING:
    from scopelink.cli.mount_session import DeviceCommand
    from scopelink.drivers.skytracker.memory import SlotMirror
    from scopelink.mount import Mount

__all__ = ["DEFAULT_PUSHTO_INTERVAL_S", "register"]

DEFAULT_PUSHTO_INTERVAL_S: Final = 0.5
"""``pushto`` refreshes its line twice a second."""
KINDS: Final = ("skytracker", "skycommander")
MAX_PLAN_BYTES: Final = 1 << 20
"""A plan file larger than 1 MiB is refused unread (a wrong path such as /dev/zero)."""

_EXAMPLES = """\
examples:
  scopelink skycommander upload M 31 "NGC 7000" Vega -d skycommander:/dev/ttyUSB0
  scopelink skycommander upload --plan tonight.txt --from 10 -d skytracker:/dev/ttyUSB0
  scopelink skycommander slots -d skycommander:/dev/ttyUSB0
  scopelink skycommander clear -d skycommander:/dev/ttyUSB0     (or: clear 3 4, clear --forget)
  scopelink skycommander pushto M 13 -d skycommander:/dev/ttyUSB0     live until Ctrl-C

plan file: one object per line, '#' comments; '@NN' first puts it in slot NN; 'RA DEC' (J2000)
lines may be named after '=' (a comet's positions for the night):
  M 31
  @12 NGC 7000
  05:35:17 -05:23:28 = C/2023 A3 at 21h
"""


def register(commands: CommandParsers) -> None:
    parser = commands.parser(
        "skycommander",
        description=(
            "The Sky Commander's memory of 59 objects (slots 00-58) and a push-to view. The "
            "device is skycommander:PORT (the Sky Commander alone on its port) or "
            "skytracker:PORT (through the Sky Tracker's bus)."
        ),
        epilog=_EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    slots = actions.add_parser("slots", help="show what scopelink last wrote to each slot")
    add_device_arguments(slots)
    slots.set_defaults(run=_run_slots)

    upload = actions.add_parser("upload", help="store objects (names, 'RA DEC', or --plan FILE)")
    upload.add_argument("objects", nargs="*", metavar="OBJECT", help="M 31, 'NGC 7000', 'RA DEC'")
    upload.add_argument("--plan", metavar="FILE", help="a plan file ('-' for stdin)")
    upload.add_argument(
        "--from",
        dest="start",
        type=int,
        default=0,
        metavar="N",
        help="first slot for objects without '@NN' (default 0)",
    )
    add_device_arguments(upload)
    accept_negative_values(upload)
    upload.set_defaults(run=_run_upload)

    clear = actions.add_parser(
        "clear", help="overwrite the slots scopelink wrote (or SLOTs) with the pole"
    )
    clear.add_argument("slots", nargs="*", type=int, metavar="SLOT", help="only these slots")
    clear.add_argument(
        "--forget",
        action="store_true",
        help="only forget the mirror; send nothing (the box keeps its objects)",
    )
    add_device_arguments(clear)
    clear.set_defaults(run=_run_clear)

    pushto = actions.add_parser("pushto", help="live distance and direction to TARGET per axis")
    pushto.add_argument("target", nargs="+", metavar="TARGET", help="a name or J2000 'RA DEC'")
    pushto.add_argument(
        "--interval",
        type=float,
        default=DEFAULT_PUSHTO_INTERVAL_S,
        metavar="S",
        help=f"seconds between refreshes (default {DEFAULT_PUSHTO_INTERVAL_S})",
    )
    pushto.add_argument("--once", action="store_true", help="print one line and exit")
    add_device_arguments(pushto)
    accept_negative_values(pushto)
    pushto.set_defaults(run=_run_pushto)
    parser.set_defaults(run=_no_action)


def _no_action(args: argparse.Namespace) -> int:  # pragma: no cover - argparse requires one
    raise CommandError("give an action: slots, upload, clear or pushto")


# --- the device and its mirror ------------------------------------------------------------------


def _command(args: argparse.Namespace) -> DeviceCommand:
    from scopelink.cli.mount_session import DeviceCommand  # noqa: PLC0415 - heavy: only to run

    command = DeviceCommand.from_args(args)
    if command.device.kind not in KINDS:
        raise CommandError(
            f"{command.device} has no Sky Commander",
            "name it skycommander:PORT (alone on its port) or skytracker:PORT (through the "
            "Sky Tracker's bus)",
        )
    return command


def _mirror(args: argparse.Namespace) -> SlotMirror:
    from scopelink.drivers.skytracker.memory import SlotMirror, mirror_key  # noqa: PLC0415

    return SlotMirror(mirror_key(_command(args).device.target))


def _on_device(
    args: argparse.Namespace, body: Callable[[Mount], Awaitable[int]], *, any_mount: bool = False
) -> int:
    """Run ``body`` on the device; only a Sky Commander's unless ``any_mount`` (push-to)."""
    from scopelink.cli.mount_session import run_on_mount  # noqa: PLC0415

    if not any_mount:
        _command(args)
    return run_on_mount(args, body)


def _coordinates(ra_hours: float, dec_deg: float) -> str:
    from scopelink.astro import format_degrees, format_hours  # noqa: PLC0415

    return f"RA {format_hours(ra_hours)} Dec {format_degrees(dec_deg)}"


def _record_error(error: Exception) -> CommandError:
    return CommandError(str(error), "the mirror is a JSON file: fix it or delete it")


# --- slots ----------------------------------------------------------------------------------------


def _run_slots(args: argparse.Namespace) -> int:
    from scopelink.mount.memory import RecordError  # noqa: PLC0415

    mirror = _mirror(args)
    try:
        entries = mirror.entries()
    except RecordError as error:
        raise _record_error(error) from None
    if not entries:
        print(f"scopelink has written no slot of this Sky Commander (mirror: {mirror.path})")
        return 0
    for slot, entry in sorted(entries.items()):
        where = _coordinates(entry.ra_j2000_hours, entry.dec_j2000_deg)
        print(f"{slot:02d}  {entry.label:<24} {where}  written {entry.written_at}")
    print(f"{len(entries)} of 59 slots written by scopelink (the box may hold others)")
    return 0


# --- upload ---------------------------------------------------------------------------------------


def _read_plan(path: str) -> str:
    """The plan's text: at most :data:`MAX_PLAN_BYTES` of UTF-8 (59 objects need a few KiB)."""
    try:
        if path == "-":
            data = sys.stdin.buffer.read(MAX_PLAN_BYTES + 1)
        else:
            with Path(path).open("rb") as file:
                data = file.read(MAX_PLAN_BYTES + 1)
        if len(data) > MAX_PLAN_BYTES:
            raise CommandError(f"nothing uploaded: the plan {path} is over {MAX_PLAN_BYTES} bytes")
        return data.decode("utf-8")
    except (OSError, UnicodeDecodeError) as error:
        raise CommandError(f"nothing uploaded: cannot read the plan {path}: {error}") from None


def _run_upload(args: argparse.Namespace) -> int:
    from scopelink.drivers.skytracker.memory import (  # noqa: PLC0415
        SlotMirror,
        UploadInterruptedError,
        mirror_key,
        upload,
    )
    from scopelink.drivers.skytracker.plan import (  # noqa: PLC0415
        PlanError,
        entries_for,
        parse_plan,
        resolve_words,
    )
    from scopelink.mount.memory import RecordError  # noqa: PLC0415

    if bool(args.objects) == bool(args.plan):
        raise CommandError("give the objects, or --plan FILE (not both)", "e.g. upload M 31 M 42")
    command = _command(args)
    now = datetime.now(UTC)
    try:
        if args.plan:
            items = parse_plan(_read_plan(args.plan))
        else:
            items = resolve_words(args.objects, now, command.site)
        entries = entries_for(
            items,
            start=args.start,
            when=now,
            site=command.site,
            sun_avoidance_deg=command.config.limits.sun_avoidance_deg,
        )
    except PlanError as error:
        raise CommandError(f"nothing uploaded: {error}") from None
    mirror = SlotMirror(mirror_key(command.device.target))
    try:
        mirror.entries()  # a damaged mirror is reported before anything is sent
    except RecordError as error:
        raise _record_error(error) from None

    async def body(mount: Mount) -> int:
        from scopelink.drivers.skytracker.memory import ObjectStorer  # noqa: PLC0415

        assert isinstance(mount, ObjectStorer)
        try:
            written = await upload(mount, mirror, entries, datetime.now(UTC))
        except UploadInterruptedError as error:
            raise CommandError(
                str(error), "'scopelink skycommander slots' shows what landed"
            ) from None
        for entry in written:
            where = _coordinates(entry.ra_j2000_hours, entry.dec_j2000_deg)
            print(f"slot {entry.slot:02d}: {entry.label}  {where}")
        print(f"{len(written)} object(s) stored in the Sky Commander's memory")
        return 0

    return _on_device(args, body)


# --- clear ----------------------------------------------------------------------------------------


def _run_clear(args: argparse.Namespace) -> int:
    from scopelink.drivers.skytracker.memory import (  # noqa: PLC0415
        SLOT_COUNT,
        ObjectStorer,
        placeholder,
    )
    from scopelink.mount.memory import RecordError  # noqa: PLC0415

    mirror = _mirror(args)
    for slot in args.slots:
        if not 0 <= slot < SLOT_COUNT:
            raise CommandError(f"slot {slot} is not 00-58")
    try:
        known = mirror.entries()
    except RecordError as error:
        raise _record_error(error) from None
    slots = sorted(set(args.slots) if args.slots else set(known))
    if args.forget:
        mirror.forget(slots if args.slots else None)
        print(f"forgot {len(slots)} slot(s); nothing was sent to the Sky Commander")
        return 0
    if not slots:
        print("scopelink has written no slot of this Sky Commander: nothing to clear")
        return 0
    command = _command(args)
    ra, dec = placeholder(command.site)

    async def body(mount: Mount) -> int:
        assert isinstance(mount, ObjectStorer)
        for slot in slots:
            await mount.store_object(slot, ra, dec)
            mirror.forget([slot])
        print(f"cleared {len(slots)} slot(s): each now holds the pole ({_coordinates(ra, dec)})")
        return 0

    return _on_device(args, body)


# --- push-to --------------------------------------------------------------------------------------


def _run_pushto(args: argparse.Namespace) -> int:
    from scopelink.astro.catalog import lookup  # noqa: PLC0415
    from scopelink.cli.stopping import until_stopped  # noqa: PLC0415
    from scopelink.cli.targets import Named, RaDec, parse_target  # noqa: PLC0415
    from scopelink.drivers.skytracker.pushto import push_to  # noqa: PLC0415

    if not args.interval > 0:
        raise CommandError(f"--interval must be positive, not {args.interval}")
    target = parse_target(args.target)
    terminal = sys.stdout.isatty()

    async def body(mount: Mount) -> int:
        if isinstance(target, Named):
            found = lookup(target.name, mount.now(), mount.site)
            ra, dec, label = found.ra_hours, found.dec_deg, found.name
        else:
            assert isinstance(target, RaDec)
            ra, dec = target.ra_hours, target.dec_deg
            label = _coordinates(ra, dec)
        async with until_stopped() as stop:
            while True:
                state = await mount.refresh()
                figures = push_to(label, ra, dec, state=state, when=state.read_at, site=mount.site)
                if terminal:
                    print(f"\r{figures.describe()}\x1b[K", end="", flush=True)
                else:
                    print(figures.describe(), flush=True)
                if args.once:
                    break
                try:
                    await asyncio.wait_for(stop.wait(), args.interval)
                except TimeoutError:
                    continue
                break
        if terminal:
            print()
        return 0

    return _on_device(args, body, any_mount=True)
