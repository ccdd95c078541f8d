"""The Sky Tracker motor box: modes, buttons, GOTO and tracking, and the Sky Commander bus.

The box drives the simulated mount's two axes (azimuth counter clockwise-positive as a compass,
altitude up-positive) and learns everything about the sky from the Sky Commander, which it
polls with ``O`` (offsets, during GOTO) and ``R`` (drive rates, while tracking) through the same
codec a PC uses, over a real link. The PC shares that link through the bus (``Q``/``A``/``q``).
"""

from __future__ import annotations

import asyncio
import contextlib
import enum
import logging
from pathlib import Path

from scopelink.links import Link, LinkClosedError
from scopelink.protocol.skytracker import (
    NEED_DATA,
    PAUSED,
    Acknowledge,
    CalibrationReply,
    CommanderClient,
    CommanderCommand,
    Direction,
    GuideSpeedReply,
    IncompleteFrame,
    OffsetsReply,
    PressDirection,
    RatesReply,
    ReadCalibration,
    ReadGuideSpeed,
    ReadOffsets,
    ReadRates,
    ReadStatus,
    ReadVersion,
    RelayToCommander,
    ReleaseBus,
    ReleaseDirections,
    Reply,
    RequestBus,
    SelectMode,
    SetCalibration,
    SetGuideSpeed,
    StatusReply,
    TrackerMode,
    TrackerServer,
    TrackerStatus,
    UnknownCommand,
    VersionReply,
    azimuth_factor,
    elevation_factor,
)
from scopelink.protocol.skytracker.messages import DEFAULT_GUIDE_SPEED_ARCSEC_PER_S
from scopelink.sim.axis import Axis
from scopelink.sim.clock import SimClock

from .commander import command_key
from .objects import Calibration, CalibrationStore
from .port import DevicePort

logger = logging.getLogger(__name__)

VERSION = VersionReply.padded("v4.0")
UTILITY_RATE_DEG_S = 4.0
"""UTIL mode: an arrow button slews at up to 4°/s (ramped by the axis' acceleration)."""
TRACK_CORRECTION_DEG_S = 8.0 / 60.0
"""TRACK mode: an arrow adds or subtracts 8 arcmin/s to the track rate."""
TICK_S = 0.5
"""How often (simulated seconds) the firmware polls the Sky Commander and updates the motors."""
GOTO_TOLERANCE_DEG = 0.0002
"""GOTO ends when both offsets are below this (well under the Sky Commander's 0.001° display)."""
GOTO_MAX_PASSES = 10
"""Correction slews before a GOTO gives up closing in and tracks where it is."""
EXCHANGE_TIMEOUT_S = 0.5
"""Real seconds the box waits for a Sky Commander reply before skipping that poll."""
FRAME_TIMEOUT_S = 1.0
"""An unfinished ``S``/``K`` frame from the PC is dropped after this long without a byte."""
DEFAULT_CALIBRATION = Calibration(azimuth_factor(20.0), elevation_factor(8.0))
"""Factory calibration: a 20-inch ground board and an 8-inch elevation bearing."""


class _Axis(enum.Enum):
    ALTITUDE = "altitude"
    AZIMUTH = "azimuth"


_BUTTON_AXES: dict[Direction, tuple[_Axis, float]] = {
    Direction.UP: (_Axis.ALTITUDE, 1.0),
    Direction.DOWN: (_Axis.ALTITUDE, -1.0),
    # Left turns the tube counter-clockwise seen from above: compass azimuth decreases.
    Direction.LEFT: (_Axis.AZIMUTH, -1.0),
    Direction.RIGHT: (_Axis.AZIMUTH, 1.0),
}
_OPPOSITE = {
    Direction.UP: Direction.DOWN,
    Direction.DOWN: Direction.UP,
    Direction.LEFT: Direction.RIGHT,
    Direction.RIGHT: Direction.LEFT,
}


class HandBox:
    """The Sky Tracker's hand controller: four arrow buttons (for tests and the dashboard)."""

    def __init__(self, tracker: SkyTracker) -> None:
        self._tracker = tracker
        self.pressed = Direction(0)

    def press(self, direction: Direction) -> None:
        """Hold ``direction`` down (several may be held)."""
        self.pressed |= direction
        self._tracker.update_motors()

    def release(self, direction: Direction | None = None) -> None:
        """Let go of ``direction``, or of every button."""
        self.pressed &= ~direction if direction is not None else Direction(0)
        self._tracker.update_motors()


class SkyTracker:
    """The Sky Tracker's firmware over two simulated axes; ``bus`` leads to the Sky Commander.

    Use as ``async with``: the firmware loop and the bus reader run while inside. Serve the PC
    port with :meth:`serve`. Calibration is kept in ``data_dir``.
    """

    def __init__(
        self,
        *,
        altitude: Axis,
        azimuth: Axis,
        clock: SimClock,
        bus: Link,
        data_dir: Path,
    ) -> None:
        self.altitude = altitude
        self.azimuth = azimuth
        self.clock = clock
        self.handbox = HandBox(self)
        self.mode = TrackerMode.UTILITY
        self.remote_pressed = Direction(0)
        self.guide_speeds_arcsec_s = (
            DEFAULT_GUIDE_SPEED_ARCSEC_PER_S,
            DEFAULT_GUIDE_SPEED_ARCSEC_PER_S,
        )
        self.calibration = CalibrationStore(data_dir, DEFAULT_CALIBRATION)
        self.track_rates_deg_min = (0.0, 0.0)
        """Last (Alt, Az counter-clockwise) drive rates read from the Sky Commander."""
        self._bus = bus
        self._bus_lock = asyncio.Lock()
        self._pc_holds_bus = False
        self._pc_port: DevicePort | None = None
        self._replies: asyncio.Queue[bytes] = asyncio.Queue()
        self._commands_seen = 0
        self._goto_landing_s: float | None = None
        self._goto_passes = 0
        self._next_tick_s = clock.elapsed()
        self._ticks = 0
        self._tick_done = asyncio.Condition()
        self._idle = asyncio.Event()
        self._tasks: list[asyncio.Task[None]] = []

    # --- life cycle ---------------------------------------------------------------------------

    async def __aenter__(self) -> SkyTracker:
        self._tasks = [
            asyncio.create_task(self._firmware(), name="sky tracker firmware"),
            asyncio.create_task(self._read_bus(), name="sky tracker bus reader"),
        ]
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)

    # --- state --------------------------------------------------------------------------------

    @property
    def pressed(self) -> Direction:
        """Directions held by the PC or on the hand box."""
        return self.remote_pressed | self.handbox.pressed

    def status(self) -> TrackerStatus:
        """What ``R`` answers."""
        return TrackerStatus.for_mode(self.mode, self.pressed)

    @property
    def pc_holds_bus(self) -> bool:
        """Whether the PC holds the Sky Commander bus."""
        return self._pc_holds_bus

    # --- stepping a stepped clock (tests) -----------------------------------------------------

    async def run_for(self, seconds: float) -> None:
        """Advance a stepped clock by ``seconds``, one firmware tick at a time, letting each
        tick finish (its Sky Commander exchanges take real time) before the next."""
        end = self.clock.elapsed() + seconds
        while (remaining := end - self.clock.elapsed()) > 0:
            await self._idle.wait()
            gap = self._next_tick_s - self.clock.elapsed()
            if gap > remaining:
                self.clock.advance(remaining)
                return
            done = self._ticks
            self.clock.advance(max(gap, 0.0))
            async with self._tick_done:
                await self._tick_done.wait_for(lambda done=done: self._ticks > done)  # type: ignore[misc]

    # --- commands -----------------------------------------------------------------------------

    def select_mode(self, mode: TrackerMode) -> None:
        """Enter ``mode`` as the U/T/D/B/G commands do (U/T/D/B during a GOTO abort it)."""
        if self.mode is TrackerMode.GOTO:
            if mode is TrackerMode.GOTO:
                return
            self._abort_goto()
            return
        self.mode = mode
        if mode is TrackerMode.GOTO:
            self._goto_landing_s = None
            self._goto_passes = 0
            self._stop_axes()
        elif mode in (TrackerMode.STANDBY, TrackerMode.UTILITY):
            self._stop_axes()
        self.update_motors()

    def press(self, direction: Direction) -> None:
        """``u``/``d``/``l``/``r``: press one direction, cancelling its opposite."""
        self.remote_pressed = (self.remote_pressed & ~_OPPOSITE[direction]) | direction
        self.update_motors()

    def release_all(self) -> None:
        """``b``: release every direction pressed by the PC."""
        self.remote_pressed = Direction(0)
        self.update_motors()

    def handle(self, command: object) -> bytes:
        """Reply bytes for one Sky Tracker command from the PC (empty for none)."""
        first_command = self._commands_seen == 0
        self._commands_seen += 1
        reply: Reply | None = None
        match command:
            case SelectMode(mode=mode):
                self.select_mode(mode)
            case PressDirection(direction=direction):
                self.press(direction)
            case ReleaseDirections():
                self.release_all()
            case ReadStatus():
                reply = StatusReply(self.status())
            case SetCalibration():
                if not first_command:
                    logger.info("S refused: not the first command since power-on (no reply)")
                    return b""
                self.calibration.write(
                    Calibration(command.azimuth_factor, command.elevation_factor)
                )
                reply = Acknowledge()
            case ReadCalibration():
                stored = self.calibration.calibration
                reply = CalibrationReply(stored.azimuth_factor, stored.elevation_factor)
            case ReadVersion():
                reply = VERSION
            case SetGuideSpeed():
                self.guide_speeds_arcsec_s = (
                    command.azimuth_arcsec_per_s,
                    command.elevation_arcsec_per_s,
                )
                self.update_motors()
            case ReadGuideSpeed():
                reply = GuideSpeedReply(*self.guide_speeds_arcsec_s)
            case ReleaseBus():
                pass  # 'q' without a grant: nothing to release
            case UnknownCommand() | IncompleteFrame():
                logger.info("Sky Tracker ignores %s", command)
            case _:
                raise TypeError(f"not a Sky Tracker command: {command!r}")
        return reply.encode() if reply is not None else b""

    # --- the PC port --------------------------------------------------------------------------

    async def serve(self, port: DevicePort) -> None:
        """Answer the PC on ``port`` until its link closes (one PC at a time, like the box)."""
        codec = TrackerServer()
        self._pc_port = port
        try:
            while True:
                try:
                    async with asyncio.timeout(FRAME_TIMEOUT_S if codec.buffered else None):
                        codec.receive_data(await port.read())
                except TimeoutError:
                    dropped = codec.discard_partial()
                    if dropped is not None:
                        self.handle(dropped)
                    continue
                if not await self._process(codec, port):
                    return
        except LinkClosedError:
            return
        finally:
            self._release_bus()
            if self._pc_port is port:
                self._pc_port = None

    async def _process(self, codec: TrackerServer, port: DevicePort) -> bool:
        while (event := codec.next_event()) is not NEED_DATA:
            if isinstance(event, RequestBus):
                self._commands_seen += 1  # answered at the PAUSED that follows
            elif event is PAUSED:
                if not await port.reply("Q", await self._answer_bus_request(codec)):
                    return False
            elif isinstance(event, RelayToCommander):
                await self._bus.write(event.data)
            elif isinstance(event, ReleaseBus) and self._pc_holds_bus:
                self._commands_seen += 1
                self._release_bus()
            elif not await port.reply(command_key(event), self.handle(event)):
                return False
        return True

    async def _answer_bus_request(self, codec: TrackerServer) -> bytes:
        if self.mode is TrackerMode.GOTO:
            return codec.refuse()
        # Waits only for an exchange of our own in progress (a few milliseconds at 9600 baud).
        await self._bus_lock.acquire()
        self._pc_holds_bus = True
        return codec.grant()

    def _release_bus(self) -> None:
        if self._pc_holds_bus:
            self._pc_holds_bus = False
            self._bus_lock.release()

    # --- the Sky Commander bus ----------------------------------------------------------------

    async def _read_bus(self) -> None:
        with contextlib.suppress(LinkClosedError):
            while True:
                data = await self._bus.read()
                port = self._pc_port
                if self._pc_holds_bus and port is not None:
                    await port.write(data)
                elif not self._pc_holds_bus:
                    self._replies.put_nowait(data)
                # Bytes after the PC released the bus but before our next poll are lost, as on
                # the real box once it stops relaying.

    async def _ask_commander(self, command: CommanderCommand) -> Reply | None:
        """One exchange of our own with the Sky Commander; None if the PC holds the bus or no
        good reply comes in time."""
        if self._bus_lock.locked():
            return None
        async with self._bus_lock:
            while not self._replies.empty():
                self._replies.get_nowait()
            client = CommanderClient()
            await self._bus.write(client.send(command))
            try:
                async with asyncio.timeout(EXCHANGE_TIMEOUT_S):
                    while (event := client.next_event()) is NEED_DATA:
                        client.receive_data(await self._replies.get())
            except TimeoutError:
                logger.info("no reply from the Sky Commander to %s", command.describe())
                return None
        return event if isinstance(event, Reply) else None

    # --- firmware -----------------------------------------------------------------------------

    async def _firmware(self) -> None:
        while True:
            self._idle.set()
            await self.clock.sleep_until(self._next_tick_s)
            self._idle.clear()
            self._next_tick_s = self.clock.elapsed() + TICK_S
            try:
                await self._tick()
            except LinkClosedError:
                logger.info("Sky Commander bus closed")
                return
            finally:
                async with self._tick_done:
                    self._ticks += 1
                    self._tick_done.notify_all()

    async def _tick(self) -> None:
        if self.mode is TrackerMode.GOTO:
            await self._goto_step()
        elif self.mode in (TrackerMode.TRACK, TrackerMode.GUIDE):
            reply = await self._ask_commander(ReadRates())
            if isinstance(reply, RatesReply) and self.mode in (
                TrackerMode.TRACK,
                TrackerMode.GUIDE,
            ):
                self.track_rates_deg_min = (reply.altitude, reply.azimuth)
                self.update_motors()

    async def _goto_step(self) -> None:
        now = self.clock.elapsed()
        if self._goto_landing_s is not None and now < self._goto_landing_s:
            return
        reply = await self._ask_commander(ReadOffsets())
        if self.mode is not TrackerMode.GOTO or not isinstance(reply, OffsetsReply):
            return
        close = max(abs(reply.altitude), abs(reply.azimuth)) < GOTO_TOLERANCE_DEG
        if close or self._goto_passes >= GOTO_MAX_PASSES:
            logger.info("GOTO done after %d slews; tracking", self._goto_passes)
            self.mode = TrackerMode.TRACK
            reply_rates = await self._ask_commander(ReadRates())
            if isinstance(reply_rates, RatesReply):
                self.track_rates_deg_min = (reply_rates.altitude, reply_rates.azimuth)
            self.update_motors()
            return
        self._goto_passes += 1
        at = self.clock.elapsed()
        altitude_target = self.altitude.position_at(at) + reply.altitude
        azimuth_target = self.azimuth.position_at(at) - reply.azimuth
        self._goto_landing_s = max(
            self.altitude.slew_to(altitude_target, max_rate_deg_s=UTILITY_RATE_DEG_S, at=at),
            self.azimuth.slew_to(azimuth_target, max_rate_deg_s=UTILITY_RATE_DEG_S, at=at),
        )

    def _abort_goto(self) -> None:
        logger.info("GOTO aborted: ramping down to UTILITY mode")
        self.mode = TrackerMode.UTILITY
        self._goto_landing_s = None
        self._stop_axes()
        self.update_motors()

    def _stop_axes(self) -> None:
        self.altitude.stop()
        self.azimuth.stop()

    def update_motors(self) -> None:
        """Set both axis rates from the mode, the track rates and the buttons held."""
        if self.mode in (TrackerMode.GOTO, TrackerMode.STANDBY):
            return
        pressed = self.pressed
        rates = {_Axis.ALTITUDE: 0.0, _Axis.AZIMUTH: 0.0}
        if self.mode is not TrackerMode.UTILITY:
            altitude_rate, azimuth_ccw_rate = self.track_rates_deg_min
            rates = {_Axis.ALTITUDE: altitude_rate / 60.0, _Axis.AZIMUTH: -azimuth_ccw_rate / 60.0}
        for direction, (axis, sign) in _BUTTON_AXES.items():
            if direction in pressed:
                rates[axis] += sign * self._button_rate_deg_s(axis)
        for axis, rate in rates.items():
            motor = self.altitude if axis is _Axis.ALTITUDE else self.azimuth
            motor.set_rate(max(-motor.max_rate_deg_s, min(motor.max_rate_deg_s, rate)))

    def _button_rate_deg_s(self, axis: _Axis) -> float:
        if self.mode is TrackerMode.UTILITY:
            return UTILITY_RATE_DEG_S
        if self.mode is TrackerMode.TRACK:
            return TRACK_CORRECTION_DEG_S
        azimuth_speed, elevation_speed = self.guide_speeds_arcsec_s
        return (elevation_speed if axis is _Axis.ALTITUDE else azimuth_speed) / 3600.0
