"""``scopelink emulate DEVICE --replay FILE``: the recording, checked, as an emulated device."""

from __future__ import annotations

import sys

from scopelink.cli.errors import CommandError
from scopelink.decode.recording import RecordingError
from scopelink.servers.hosting import WireSpeed
from scopelink.servers.replay import Divergence, ReplayDevice, load_recording

__all__ = ["replay_device"]


def replay_device(path: str, emulated: str, wire: WireSpeed | None) -> ReplayDevice:
    """The device answering from ``path``; refuses a recording of another kind of device."""
    try:
        recording = load_recording(path)
    except OSError as error:
        raise CommandError(f"cannot read {path}: {error.strerror}") from None
    except RecordingError as error:
        raise CommandError(f"{path}: {error}", "record one with 'scopelink record'") from None
    recorded = recording.protocol
    if recorded is not None and recorded.value != emulated:
        raise CommandError(
            f"{path} was recorded from a {recorded.value} device",
            f"replay it with: scopelink emulate {recorded.value} --replay {path}",
        )
    print(
        f"replaying {len(recording.exchanges())} exchanges from {path}",
        file=sys.stderr,
        flush=True,
    )
    return ReplayDevice(recording, wire=wire, report=_report)


def _report(divergence: Divergence) -> None:
    print(divergence.describe(), file=sys.stderr, flush=True)
