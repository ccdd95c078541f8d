"""What `bench.fuzz` and tests/reliability/test_fuzz_parsers.py fuzz: one `Target` per parser.

A target is a few valid inputs (its seeds: frames, requests, files) and a `check` that feeds one
input to the parser, in chunks the given `random.Random` chooses, and raises `FuzzFailureError`
when an invariant breaks. Any other exception escaping `check` is a crash: the only exceptions a
parser may raise are the documented error types, which `check` catches itself.

The invariants, per parser (docs/reliability-fuzzing.md has the table):

- only the documented event types come out, and every event consumes at least one byte (no
  parser can loop on its own input);
- every byte is accounted for (stream offset + bytes held back = bytes fed);
- round trips: a decoded command re-encodes to a frame that decodes to the same command;
- recovery: after any garbage, the spec's recovery step (an inter-byte pause, a ``#``, ``reset()``
  and a unique echo, ``abandon_reply()``) leaves the parser in step, and valid frames sent next
  come out exactly, in any chunking.

One module per target family: `synscan`, `skytracker` (Sky Tracker and Sky Commander),
`planetarium` (LX200, SkyFi, Stellarium), `web` (Alpaca and dashboard HTTP), `text_inputs`
(decode traces, the settings file, CLI targets) and `devices` (the emulated devices and the
Alpaca setters behind the parsers); `base` holds what they share.
"""

from __future__ import annotations

from bench.fuzz_targets import devices, planetarium, skytracker, synscan, text_inputs, web
from bench.fuzz_targets.base import FuzzFailureError, Target, chunks
from bench.fuzz_targets.skytracker import check_commander_server
from bench.fuzz_targets.synscan import check_synscan_server

__all__ = [
    "TARGETS",
    "FuzzFailureError",
    "Target",
    "check_commander_server",
    "check_synscan_server",
    "chunks",
    "target_named",
]

TARGETS: tuple[Target, ...] = (
    *synscan.TARGETS,
    *skytracker.TARGETS,
    *planetarium.TARGETS,
    *web.TARGETS,
    text_inputs.TRACE_TEXT,
    *devices.SERIAL_DEVICES,
    text_inputs.CLI_TARGET,
    text_inputs.CONFIG,
    devices.ALPACA_SETTERS,
)
"""Every target, in a fixed order: an input's generator is seeded with its target's index, so
the order keeps every reported ``TARGET:INDEX`` reproducible."""


def target_named(name: str) -> Target:
    for target in TARGETS:
        if target.name == name:
            return target
    raise KeyError(f"no fuzz target {name!r} (known: {', '.join(t.name for t in TARGETS)})")
