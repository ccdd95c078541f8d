"""Opening a device by its string: what a DEVICE string names, and the :class:`Mount` that
drives it (the CLI's DEVICE argument, ``scopelink serve``, library users; docs/cli.md).

Forms:

- ``sim`` or ``sim:PRESET`` (``sim:eq6``, ``sim:az-gti``, ...): the built-in simulated mount, in
  this process (it starts afresh every run);
- ``synscan:LINK``: a SynScan hand control; ``skytracker:LINK``: a Sky Tracker motor box
  (its Sky Commander, if fitted, answers on the same line);
- ``skycommander:LINK``: a Sky Commander alone on its own port (push-to: reads, syncs and its
  object memory; no motion);
- ``LINK`` alone: try SynScan, then Sky Tracker (autodetect).

LINK is anything :func:`scopelink.links.open_link` opens: ``/dev/ttyUSB0``, ``COM3``,
``tcp://host:11880``, ``socket://host:port``, ``rfc2217://host:port``, a pty path.
"""

from __future__ import annotations

import contextlib
import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:  # the CLI builds its parsers from EXAMPLES: no numpy before a command runs
    from scopelink.astro import Site
    from scopelink.mount import Limits, Mount

__all__ = [
    "AUTODETECT_TIMEOUT_S",
    "KINDS",
    "SERVE_KIND",
    "DeviceOpenError",
    "DeviceSpec",
    "create_mount",
    "open_mount",
    "parse_device",
]

_log = logging.getLogger(__name__)

KINDS: Final = ("sim", "synscan", "skytracker", "skycommander", "serve")
SERVE_KIND: Final = "serve"
"""``serve`` (or ``serve:PID``): the mount of a ``scopelink serve`` running on this machine for
this user; the command line drives it through that serve (cli/serve_mount.py), nothing here
opens it."""
DEFAULT_SIM_PRESET: Final = "eq6"
AUTODETECT_TIMEOUT_S: Final = 1.5
"""Reply timeout while probing a device of unknown kind: long enough for any real hand control
(replies come within ~100 ms), short enough that trying the second protocol is quick."""

EXAMPLES: Final = (
    "sim, sim:az-gti, synscan:/dev/ttyUSB0, synscan:tcp://192.168.4.1:11880, "
    "skytracker:/dev/ttyUSB0, serve (a running scopelink serve), or a bare port to autodetect"
)


class DeviceOpenError(Exception):
    """The DEVICE string is malformed, or nothing usable answered on it."""

    def __init__(self, message: str, hint: str = "", *, unopenable: bool = False) -> None:
        super().__init__(message)
        self.hint = hint
        self.unopenable = unopenable
        """The port or address itself would not open (nothing was asked of a device)."""


@dataclass(frozen=True, slots=True)
class DeviceSpec:
    """A parsed DEVICE string: ``kind`` is None when it must be detected; ``target`` is the link
    spec (or the simulator preset)."""

    kind: str | None
    target: str

    def __str__(self) -> str:
        if self.kind and self.target:
            return f"{self.kind}:{self.target}"
        return self.kind or self.target


def parse_device(text: str) -> DeviceSpec:
    """Split ``kind:target``; a prefix that is no kind belongs to the link (``tcp://...``)."""
    text = text.strip()
    if not text:
        raise DeviceOpenError("empty device", f"give one of: {EXAMPLES}")
    if text == "sim":
        return DeviceSpec("sim", DEFAULT_SIM_PRESET)
    if text.lower() == SERVE_KIND:
        return DeviceSpec(SERVE_KIND, "")
    kind, colon, rest = text.partition(":")
    _refuse_a_mistyped_kind(text, kind if colon and not rest.startswith("//") else None, rest)
    if colon and kind.lower() in KINDS and not rest.startswith("//"):
        kind = kind.lower()
        if not rest.strip():
            raise DeviceOpenError(f"device {text!r} names no port", f"give one of: {EXAMPLES}")
        if kind == "sim":
            from scopelink.sim import PRESETS  # noqa: PLC0415 - numpy: only for a sim device

            preset = rest.strip().lower()
            if preset not in PRESETS:
                raise DeviceOpenError(
                    f"no simulated mount called {preset!r}",
                    "presets: " + ", ".join(sorted(PRESETS)),
                )
            return DeviceSpec("sim", preset)
        if kind == SERVE_KIND and not rest.strip().isdigit():
            raise DeviceOpenError(
                f"{text!r}: serve takes the PID of a running scopelink serve",
                "give serve (the one running) or serve:PID",
            )
        return DeviceSpec(kind, rest.strip())
    return DeviceSpec(None, text)


def _refuse_a_mistyped_kind(text: str, kind: str | None, rest: str) -> None:
    """``simm`` or ``synscn:/dev/ttyUSB0`` is a kind mistyped, not a port to open: say which
    kind was probably meant (a bare word with no path separator that is close to a kind, or a
    prefix before ``:`` that is close to one). A port really named like that is still reached
    as ``./simm`` or with its kind, ``synscan:simm``."""
    import difflib  # noqa: PLC0415 - only when a device is parsed

    if kind is not None:
        word, meant = kind.lower(), "{}:" + rest
    elif not any(c in text for c in "/\\:"):
        word, meant = text.lower(), "{}"
    else:
        return
    if not word or word in KINDS:
        return
    close = difflib.get_close_matches(word, KINDS, n=1)  # default cutoff, 0.6
    if close:
        suggestion = meant.format(close[0])
        raise DeviceOpenError(
            f"unknown device kind {kind or text!r}: did you mean {suggestion}?",
            f"device kinds: {', '.join(KINDS)}; for example {EXAMPLES}",
        )


def create_mount(
    spec: DeviceSpec,
    *,
    site: Site,
    limits: Limits | None = None,
    clock_rate: float = 1.0,
    timeout_s: float | None = None,
) -> Mount:
    """The (not yet connected) mount for a spec of known kind. ``clock_rate`` speeds up the
    simulator's clock; ``timeout_s`` bounds each reply of a real device (driver default if None)."""
    if spec.kind == "sim":
        from scopelink.sim import PRESETS, SimClock, SimulatedMount  # noqa: PLC0415 - if used

        return SimulatedMount(
            PRESETS[spec.target], site=site, limits=limits, clock=SimClock(rate=clock_rate)
        )
    if spec.kind == "synscan":
        from scopelink.drivers.synscan import SynScanMount  # noqa: PLC0415 - heavy, only if used

        if timeout_s is None:
            return SynScanMount(spec.target, site=site, limits=limits)
        return SynScanMount(spec.target, site=site, limits=limits, timeout_s=timeout_s)
    if spec.kind == "skytracker":
        from scopelink.drivers.skytracker import SkyTrackerMount  # noqa: PLC0415 - only if used

        if timeout_s is None:
            return SkyTrackerMount(spec.target, site=site, limits=limits)
        return SkyTrackerMount(spec.target, site=site, limits=limits, timeout_s=timeout_s)
    if spec.kind == "skycommander":
        from scopelink.drivers.skytracker import SkyCommanderMount  # noqa: PLC0415 - if used

        if timeout_s is None:
            return SkyCommanderMount(spec.target, site=site, limits=limits)
        return SkyCommanderMount(spec.target, site=site, limits=limits, timeout_s=timeout_s)
    if spec.kind == SERVE_KIND:
        raise DeviceOpenError(
            "a running scopelink serve is driven by the command line only",
            "give serve's own --device the device itself (sim, synscan:PORT...)",
        )
    raise DeviceOpenError(f"cannot create a mount of unknown kind for {spec}")


async def open_mount(
    spec: str | DeviceSpec,
    site: Site,
    limits: Limits | None = None,
    *,
    clock_rate: float = 1.0,
    timeout_s: float | None = None,
) -> Mount:
    """The connected mount ``spec`` names (see the module docstring for the forms).

    Without a kind, SynScan is tried first (its echo ``K`` is harmless to a Sky Tracker, whose
    driver resynchronises the line anyway), then Sky Tracker, each with a short reply timeout.
    Raises :class:`DeviceOpenError` with a hint when nothing answered or the port cannot be opened.
    """
    parsed = parse_device(spec) if isinstance(spec, str) else spec
    if parsed.kind is not None:
        mount = create_mount(
            parsed, site=site, limits=limits, clock_rate=clock_rate, timeout_s=timeout_s
        )
        try:
            await _connect(mount, parsed)
        except DeviceOpenError:
            await _close_quietly(mount)  # a caller trying again must find the port free
            raise
        return mount
    failures: list[str] = []
    for kind in ("synscan", "skytracker"):
        candidate = DeviceSpec(kind, parsed.target)
        mount = create_mount(
            candidate, site=site, limits=limits, timeout_s=timeout_s or AUTODETECT_TIMEOUT_S
        )
        try:
            await _connect(mount, candidate)
        except DeviceOpenError as error:
            _log.debug("autodetect: not %s: %s", kind, error)
            await _close_quietly(mount)  # the next kind needs the port to itself
            if error.unopenable:
                raise  # no other kind would open it either: say so once
            failures.append(f"{kind}: {error}")
            continue
        return mount
    raise DeviceOpenError(
        f"nothing recognisable answered on {parsed.target} ({'; '.join(failures)})",
        "check the cable and that the hand control is powered and past its start-up "
        "screens; name the kind (synscan:PORT or skytracker:PORT) to skip detection; "
        "'scopelink doctor PORT' says what answers there",
    )


_PORT_HINT: Final = (
    "'scopelink ports' lists the serial ports; check the path and your permissions "
    "(the dialout group on Linux); 'scopelink doctor PORT' says what is wrong"
)


_ADDRESS_HINT: Final = (
    "check the address and port, and that the device (or 'scopelink emulate') listens there"
)


def _unopenable(spec: DeviceSpec, message: str) -> DeviceOpenError:
    """One line for a port that would not open: the innermost "cannot open ..." of the link's
    and the driver's messages (each layer adds its own), and the hint for that kind of link."""
    start = message.rfind("cannot open ")
    text = message[start:] if start >= 0 else f"cannot open {spec.target}: {message}"
    hint = _ADDRESS_HINT if "://" in spec.target else _PORT_HINT
    return DeviceOpenError(text, hint, unopenable=True)


async def _close_quietly(mount: Mount) -> None:
    """Close the link a failed connection attempt may have left open."""
    from scopelink.links import LinkError  # noqa: PLC0415 - see the imports at the top
    from scopelink.mount import MountError  # noqa: PLC0415

    with contextlib.suppress(MountError, LinkError):
        await mount.disconnect()


async def _connect(mount: Mount, spec: DeviceSpec) -> None:
    from scopelink.links import LinkError  # noqa: PLC0415 - see the imports at the top
    from scopelink.mount import MountError  # noqa: PLC0415

    try:
        await mount.connect()
    except LinkError as error:
        raise _unopenable(spec, str(error)) from None
    except MountError as error:
        # Drivers report a port that would not open as a MountError saying "cannot open".
        if "cannot open" in str(error):
            raise _unopenable(spec, str(error)) from None
        raise DeviceOpenError(f"{spec}: {error}") from None
    except TimeoutError:
        raise DeviceOpenError(f"{spec}: no reply") from None
