"""Text a user types or hands over: a ``scopelink decode`` trace, the settings file, a CLI
target."""

from __future__ import annotations

import random
from dataclasses import astuple

from bench.fuzz_targets.base import (
    SCRATCH_DIR,
    Target,
    chunks,
    expect,
)
from scopelink.cli.config import ConfigError, load_config
from scopelink.cli.errors import CommandError
from scopelink.cli.targets import AltAz, RaDec, parse_target
from scopelink.decode import Direction, Protocol, TraceInputError, annotate, parse_trace


def check_trace_text(data: bytes, rng: random.Random) -> None:
    """``scopelink decode`` input: escaped text, hex or an INDI log -> chunks -> annotations."""
    hex_input = rng.random() < 0.3
    try:
        trace = parse_trace(list(chunks(data, rng)), hex_input=hex_input)
    except TraceInputError as error:
        expect(0 <= error.column <= len(error.line), f"column {error.column} outside its line")
        return
    annotations = annotate(trace, rng.choice(list(Protocol)))
    # docs/decode.md: every byte is in exactly one annotation; untagged traces read in order,
    # tagged ones per direction (a reply may gather bytes from several chunks).
    total = sum(len(chunk.data) for chunk in trace)
    covered = sum(len(annotation.data) for annotation in annotations)
    expect(covered == total, f"annotations hold {covered} bytes of {total}")
    expect(all(0 <= a.offset <= total for a in annotations), "an annotation outside the trace")
    if all(chunk.direction is None for chunk in trace):
        position = 0
        for annotation in annotations:
            if annotation.data:
                expect(annotation.offset == position, f"annotation at {annotation.offset}")
                position += len(annotation.data)
    elif all(chunk.direction is not None for chunk in trace):
        for direction in Direction:
            sent = b"".join(chunk.data for chunk in trace if chunk.direction is direction)
            read = b"".join(a.data for a in annotations if a.direction is direction)
            expect(read == sent, f"{direction.value} bytes annotated as {read!r}, sent {sent!r}")


# ---------------------------------------------------------------------------------------- config


def check_config(data: bytes, rng: random.Random) -> None:
    """The settings file reader on any bytes: a Config or a ConfigError naming the file."""
    SCRATCH_DIR.mkdir(exist_ok=True)
    path = SCRATCH_DIR / "config.toml"
    path.write_bytes(data)
    try:
        config = load_config(path)
    except ConfigError as error:
        expect(str(path) in str(error), f"the error does not name the file: {error}")
        return
    expect(config.path == path, "config read from the wrong place")


_CONFIG_SEEDS = (
    b'device = "synscan:/dev/ttyUSB0"\n\n[site]\nlatitude = 51.4779\nlongitude = -0.0015\n'
    b"elevation = 46\npressure = 1013.25\ntemperature = 10.5\nhumidity = 0.5\n",
    b"[horizon]\naltitude = 10\nprofile = [[0, 5], [90, 20.5], [180, 0], [270, 15]]\n\n"
    b"[limits]\nmax_altitude = 85\n",
    b'[servers]\nhost = "0.0.0.0"\nalpaca = 11111\nlx200 = false\nstellarium = 0\n'
    b"synscan = 11880\n",
    b'device = "sim"\n[site]\nlatitude = -33.86\nlongitude = 151.2\n[limits]\n',
)


def check_cli_target(data: bytes, rng: random.Random) -> None:
    """A TARGET on the command line (``goto``, ``sync``): a name, or two angles in range."""
    words = data.decode("utf-8", "replace").split(" ")
    altaz = rng.random() < 0.3
    try:
        target = parse_target(words, altaz=altaz)
    except CommandError:
        return
    if isinstance(target, RaDec | AltAz):
        # Ranges are the Mount's to check (InvalidValueError names the bound): "82 0" is read.
        expect(all(isinstance(angle, float) for angle in astuple(target)), f"{target}")
    else:
        expect(bool(target.name) and target.name == target.name.strip(), f"{target!r}")


TRACE_TEXT = Target(
    "decode-trace-text",
    (
        b"-> e\n<- 34AB0500,12CE0500#",
        b"TX: 50 02 11 24\nRX: 06 21 #",
        b"> K\\x80\n< \\x80#",
        b"[DEBUG] CMD <e>\n[DEBUG] RES <34AB0500,12CE0500#>",
        b"CMD <50 03 10 16 00 00 00 02>\nRES <12 34 #>",
        b"CMD: 0XD\nRES: 05.500 -20.250",
        b"PC: Q\nST: A\nPC: L99 05.587 -05.391\\r\nSC: A",
    ),
    check_trace_text,
    b"\\\n<->:xrn0 ",
    max_size=512,
)
CLI_TARGET = Target(
    "cli-target",
    (
        b"05:35:17 -05:23:28",
        b"5.5 -5.4",
        b"5h35m17s -5\xc2\xb023'28\"",
        b"5 35 17 -5 23 28",
        b"M31",
    ),
    check_cli_target,
    b" :.+-hmsd0123456789'\"",
)
CONFIG = Target("config", _CONFIG_SEEDS, check_config, b'[]{}=."\n#0123456789-', max_size=6000)
