"""What an emulator for a test is made of, checked before anything starts.

:class:`EmulatorSpec` names the device, the transport, the mount model, firmware, site, faults and
clock; :func:`build` makes the (not yet started) device in the running event loop. Nonsense (an EQ6
behind a Sky Tracker, firmware for a device that has no choice, a negative clock rate) raises
:class:`EmulatorSpecError` with one line.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import datetime
from pathlib import Path

from scopelink.astro import Site
from scopelink.cli.options import DEFAULT_SITE
from scopelink.mount import Limits
from scopelink.protocol.synscan import Version
from scopelink.servers.faults import Fault, FaultInjector, FaultSpecError
from scopelink.servers.hosting import SERIAL_9600_8N1, WireSpeed
from scopelink.servers.skytracker import SkyCommanderEmulator, SkyTrackerEmulator
from scopelink.servers.skytracker.emulator import require_alt_az
from scopelink.servers.synscan import DEFAULT_FIRMWARE, SynScanConfig, SynScanEmulator
from scopelink.sim import DEFAULT_EPOCH, PRESETS, SimClock, SimulatedMount

__all__ = ["DEVICES", "TRANSPORTS", "Built", "Device", "EmulatorSpec", "EmulatorSpecError", "build"]

DEVICES = ("synscan", "skytracker", "skycommander")
"""The emulators a test can start: the SynScan hand control, the Sky Tracker with its Sky
Commander on the bus, the Sky Commander alone."""

TRANSPORTS = ("tcp", "pty")
"""Where a test's client reaches it: a TCP port on 127.0.0.1 (default) or a pseudo-terminal."""

DEFAULT_MODELS = {"synscan": "EQ6", "skytracker": "Sky Tracker", "skycommander": "Sky Tracker"}
"""The mount preset behind each device unless a test names another."""

DEVICE_LIMITS = Limits(sun_avoidance_deg=0.0)
"""An emulated device knows nothing of the Sun, as the real one (as ``scopelink emulate``)."""


class EmulatorSpecError(ValueError):
    """A parameter no such device can have; the message is one line."""


SiteLike = Site | tuple[float, float] | str


@dataclass(frozen=True)
class EmulatorSpec:
    """One emulator for a test; every field is a keyword of the fixtures' marker and factories.

    ``device``: one of :data:`DEVICES`. ``transport``: ``"tcp"`` or ``"pty"``. ``model``: a mount
    preset (``"EQ6"``, ``"HEQ5"``, ``"AZ-GTi"``, ``"Dob GOTO"``, ``"Sky Tracker"``; any case).
    ``model_code``, ``firmware`` (``"4.39.05"``) and ``aligned``: the SynScan hand control's
    ``m``, ``V`` and ``J``. ``site``: a :class:`~scopelink.astro.Site`, ``(lat, lon)`` or
    ``"LAT,LON"`` (default Greenwich, as the CLI). ``faults``: fault rules as ``scopelink emulate
    --fault`` takes them (``"e:drop"``) or :class:`~scopelink.servers.faults.Fault` s (one or a
    list), ``seed``
    for probabilistic ones. ``clock_rate``: simulated seconds per real second (1 real time, 100
    for gotos 100 times sooner, 0 stepped: time moves only by ``handle.advance()``); ``start``:
    the simulated UTC date at start. ``pacing``: replies at 9600 baud (off: at once).
    ``data_dir``: the Sky Tracker's and Sky Commander's non-volatile memory (default: a fresh
    temporary directory, removed when the emulator stops).
    """

    device: str = "synscan"
    transport: str = "tcp"
    model: str | None = None
    model_code: int | None = None
    firmware: str | None = None
    aligned: bool = True
    site: SiteLike = DEFAULT_SITE
    faults: str | Fault | Sequence[str | Fault] = field(default_factory=tuple)
    seed: int | None = None
    clock_rate: float = 1.0
    start: datetime = DEFAULT_EPOCH
    pacing: bool = True
    data_dir: Path | None = None

    def __post_init__(self) -> None:
        # frozen: the checked, lower-case names replace what was given ("SynScan", "PTY")
        object.__setattr__(self, "device", _one_of("device", self.device, DEVICES))
        object.__setattr__(self, "transport", _one_of("transport", self.transport, TRANSPORTS))
        for name in ("aligned", "pacing"):
            if not isinstance(getattr(self, name), bool):
                raise EmulatorSpecError(f"{name} is True or False, not {getattr(self, name)!r}")
        preset = PRESETS.get(self.model_name.lower())
        if preset is None:
            _one_of("model", self.model_name, tuple(model.name for model in PRESETS.values()))
        if self.device != "synscan":
            self._check_sky_tracker_side()
        elif preset is not None and preset.synscan_model_code is None and self.model_code is None:
            raise EmulatorSpecError(
                f"a SynScan hand control does not drive the {preset.name}: give model_code too"
            )
        try:
            self.make_site()
            self.make_clock()
            self.make_faults()
            self.make_firmware()
            self.synscan_config()
        except (ValueError, TypeError, FaultSpecError) as error:
            raise EmulatorSpecError(str(error).splitlines()[0]) from None

    def _check_sky_tracker_side(self) -> None:
        for name in ("model_code", "firmware"):
            if getattr(self, name) is not None:
                raise EmulatorSpecError(
                    f"{name} is the SynScan hand control's; the {self.device} has its own"
                )
        if not self.aligned:
            raise EmulatorSpecError(
                f"aligned=False is the SynScan hand control's, not the {self.device}'s"
            )
        mount = SimulatedMount(
            PRESETS[self.model_name.lower()], site=Site(0.0, 0.0), clock=SimClock.stepped()
        )
        try:
            require_alt_az(mount, "Sky Tracker" if self.device == "skytracker" else "Sky Commander")
        except ValueError as error:
            raise EmulatorSpecError(str(error)) from None

    @property
    def model_name(self) -> str:
        return self.model if self.model is not None else DEFAULT_MODELS.get(self.device, "")

    def make_site(self) -> Site:
        if isinstance(self.site, Site):
            return self.site
        text = self.site if isinstance(self.site, str) else ",".join(map(str, self.site))
        try:
            latitude, longitude = (float(part) for part in text.split(","))
        except ValueError:
            raise ValueError(f"site {self.site!r} is not LAT,LON like 40.4,-3.7") from None
        return Site(latitude, longitude)

    def make_clock(self) -> SimClock:
        return SimClock(start=self.start, rate=self.clock_rate)

    def make_faults(self) -> FaultInjector:
        given = [self.faults] if isinstance(self.faults, str | Fault) else self.faults
        rules = [rule if isinstance(rule, Fault) else Fault.parse(rule) for rule in given]
        return FaultInjector(rules, seed=self.seed)

    def make_firmware(self) -> Version:
        if self.firmware is None:
            return DEFAULT_FIRMWARE
        try:
            major, minor, patch = (int(part) for part in self.firmware.split("."))
        except ValueError:
            raise ValueError(f"firmware {self.firmware!r} is not a version like 4.39.05") from None
        return Version(major, minor, patch)

    def synscan_config(self) -> SynScanConfig:
        code = self.model_code
        if code is None:
            code = PRESETS[self.model_name.lower()].synscan_model_code or 0
        return SynScanConfig(model=code, firmware=self.make_firmware(), aligned=self.aligned)


def _one_of(name: str, value: object, choices: tuple[str, ...]) -> str:
    """The choice ``value`` names, whatever its case; else a one-line refusal."""
    for choice in choices:
        if isinstance(value, str) and value.lower() == choice.lower():
            return choice
    raise EmulatorSpecError(f"{name} {value!r} is not one of {', '.join(choices)}")


Device = SynScanEmulator | SkyTrackerEmulator | SkyCommanderEmulator


@dataclass(frozen=True, slots=True)
class Built:
    """A device made from a spec (not yet started), its simulated mount, and the line its replies
    leave at when the host paces them (the Sky Tracker's and Sky Commander's ports pace
    themselves: None)."""

    device: Device
    mount: SimulatedMount
    wire: WireSpeed | None


def build(spec: EmulatorSpec, data_dir: Path) -> Built:
    """The device ``spec`` describes, its Sky Tracker memory in ``data_dir``."""
    mount = SimulatedMount(
        PRESETS[spec.model_name.lower()],
        site=spec.make_site(),
        clock=spec.make_clock(),
        limits=DEVICE_LIMITS,
    )
    faults = spec.make_faults()
    if spec.device == "synscan":
        wire = SERIAL_9600_8N1 if spec.pacing else None
        config = spec.synscan_config()
        return Built(SynScanEmulator(mount, config, faults=faults, wire=wire), mount, wire)
    if spec.device == "skytracker":
        return Built(
            SkyTrackerEmulator(mount, data_dir, faults=faults, pace=spec.pacing), mount, None
        )
    return Built(
        SkyCommanderEmulator(mount, data_dir, faults=faults, pace=spec.pacing), mount, None
    )
