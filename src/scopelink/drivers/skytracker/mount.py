"""``SkyTrackerMount``: the Mount API over the PC <-> Sky Tracker (+ Sky Commander) line.

The Sky Tracker box moves the motors; the Sky Commander behind its bus knows where the scope
points (J2000, three decimals) and holds the current object. Position reads and object uploads
go through the bus (``Q`` ... ``q``); modes, arrows, status, guide speed and calibration are
Sky Tracker commands. Decisions where the spec is silent are in ``docs/drivers-skytracker.md``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from dataclasses import replace
from typing import Any, Self

from scopelink.astro import Site
from scopelink.drivers.common import LinkFactory
from scopelink.links import LinkError
from scopelink.mount import (
    DeviceError,
    GuideDirection,
    InvalidValueError,
    LimitError,
    MountAxis,
    MountError,
    MountState,
    NotConnectedError,
    NotSupportedError,
    TrackingMode,
)
from scopelink.mount.scheduling import Priority
from scopelink.protocol.skytracker import (
    Acknowledge,
    LoadObject,
    PressDirection,
    ReadStatus,
    Realign,
    ReleaseDirections,
    Reply,
    SelectMode,
    SetGuideSpeed,
    TrackerCommand,
    TrackerMode,
)

from .base import BOX_TRACKING
from .calibration import CalibrationFactors, CalibrationRuleError
from .memory import stored_object
from .motion import axis_motion, guide_button, plan_buttons
from .rates import SkyTrackerRates
from .realign import realign_on

__all__ = ["SkyTrackerMount", "SlewInProgressError"]

logger = logging.getLogger(__name__)


class SlewInProgressError(MountError):
    """A GOTO is running: the request would abort it (or needs the bus the GOTO keeps busy)."""


def _other(axis: MountAxis) -> MountAxis:
    return MountAxis.SECONDARY if axis is MountAxis.PRIMARY else MountAxis.PRIMARY


class SkyTrackerMount(SkyTrackerRates):
    """A Sky Tracker box (with its Sky Commander) on a link.

    ``link`` is a link spec as for :func:`scopelink.links.open_link` (``/dev/ttyUSB0``,
    ``tcp://HOST:PORT``, a pty path): serial ports are opened 9600 8N2, links without a UART
    get paced sends (11 bit-times per byte). Or a coroutine function returning an open link,
    used as it is (wrap it in :func:`scopelink.links.paced` yourself if it has no UART).
    ``guide_speed_arcsec_s`` sets the ``K`` speed used by pulse guiding (default: the box's).
    """

    poll_interval_s = 0.0
    """Background polls may run back to back (within the poll policy's line cap)."""

    @classmethod
    async def open(
        cls,
        link: str | LinkFactory,
        *,
        calibration: CalibrationFactors | None = None,
        **options: Any,
    ) -> Self:
        """Construct the driver for ``link`` and connect it, writing ``calibration`` first if
        given; ``options`` are the constructor's keywords."""
        mount = cls(link, **options)
        await mount.connect(calibration=calibration)
        return mount

    async def connect(self, *, calibration: CalibrationFactors | None = None) -> None:
        """Open the link and identify: ``V``, ``k``, ``R`` and a position read through the bus.

        With ``calibration``, ``S`` is sent first of all (the box takes it only as the first
        command after power-on): a refusal raises :class:`CalibrationRuleError`, not connected.
        A lost link (see :meth:`refresh`) is opened anew.
        """
        if self._engaged and calibration is None:  # connected, or lost: reopen it now
            await self._reconnection.run_if(self._needs_reconnect, self._reconnect)
            return
        if self._line is not None:
            if not self._line.link.closed and not self._link_lost:
                return
            await self._drop_line()  # the link went away under us: open it again
        await self._open_and_identify(calibration)
        self._engaged = True

    async def disconnect(self) -> None:
        """Release the arrows, abort a GOTO (``U``), close the link. Tracking keeps running."""
        self._engaged = False
        self._link_lost = False
        line = self._line
        if line is None:
            self._publish_now()
            return
        await self._end_rate_loop()
        self._cancel_pulses()
        self._held.clear()
        try:
            if line.link.closed:
                raise NotConnectedError(f"the link {line.link.name} is closed")
            commands: list[TrackerCommand] = [ReleaseDirections()]
            if self._mode is TrackerMode.GOTO:
                commands.append(SelectMode(TrackerMode.UTILITY))
            # The status read makes sure the box has taken them before the link closes.
            await line.ask_sequence([*commands, ReadStatus()])
        except (MountError, LinkError) as error:
            logger.info("could not stop motion before disconnecting: %s", error)
        finally:
            self._line = None
            with contextlib.suppress(LinkError):
                await line.link.close()
            self._publish(replace(self.state, connected=False))

    async def write_calibration(self, factors: CalibrationFactors) -> None:
        """``S``: store calibration factors in the box's EEPROM.

        The box takes ``S`` only as the first command after it is switched on, and once. Call
        this *instead of* :meth:`connect` (it connects, sending ``S`` first); once connected,
        the rule forbids it and :class:`CalibrationRuleError` is raised without sending anything.
        """
        if self._line is not None:
            raise CalibrationRuleError(
                f"the Sky Tracker takes 'S' only as the first command after it is switched on, "
                f"and only once; {self._line.statistics.commands_sent} commands have been sent on "
                "this connection. Disconnect, switch the Sky Tracker off and on, then call "
                "write_calibration() before connect()"
            )
        await self.connect(calibration=factors)

    async def _goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``U`` if a GOTO runs (re-target), ``Q`` ``L99 ...`` ``q``, then ``G``."""
        line = self._require_commander()
        await self._release_all_buttons()
        # UTILITY first: it ends a GOTO under way (the box ignores 'G' during one), and makes
        # the status after 'G' tell a lost 'G' (still UTILITY) from a GOTO that ended at once
        # (TRACK).
        await line.ask(SelectMode(TrackerMode.UTILITY))
        self._mode = TrackerMode.UTILITY
        (reply,) = await line.commander([LoadObject.current(ra_j2000_hours, dec_j2000_deg)])
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"the Sky Commander did not acknowledge the object: {reply}")
        # 'G' has no reply: the status tells that the box took it (GOTO, or TRACK at once when
        # already on target). A lost 'G' (unbuffered port) is sent once more.
        for _ in range(2):
            replies = await line.ask_sequence([SelectMode(TrackerMode.GOTO), ReadStatus()])
            self._note_status(replies[-1])
            if self._mode in (TrackerMode.GOTO, *BOX_TRACKING):
                break
        if self._mode not in (TrackerMode.GOTO, *BOX_TRACKING):
            raise DeviceError(
                f"the Sky Tracker did not start the GOTO (status {self._status}): was 'G' lost "
                "on the line?"
            )
        self._publish_now()

    def _check_sync_now(self, state: MountState) -> None:
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                "cannot sync during a GOTO: the Sky Tracker lends no bus while it slews; "
                "wait for the GOTO to end or abort it"
            )
        super()._check_sync_now(state)

    async def _sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``Q`` ``L99 ...`` ``N`` ``q``: realign the Sky Commander on this position."""
        line = self._require_commander()
        self._check_sync_now(self.state)
        load = LoadObject.current(ra_j2000_hours, dec_j2000_deg)

        async def load_and_realign() -> Reply | None:
            return (await line.commander([load, Realign()]))[0]

        async def read_back() -> tuple[float, float]:
            after = await self._read_position(line, Priority.COMMAND, retry=True)
            self._publish_now()
            return after.ra_j2000_hours, after.dec_j2000_deg

        await realign_on(ra_j2000_hours, dec_j2000_deg, load_and_realign, read_back)

    async def store_object(self, slot: int, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        """``Q`` ``Lnn ...`` ``q``: store J2000 coordinates in slot ``slot`` (0-58) of the Sky
        Commander's memory (not made current: a GOTO under way is not disturbed, but the box
        lends no bus during one, so this waits out the bus back-off, then fails)."""
        command = stored_object(slot, ra_j2000_hours, dec_j2000_deg)
        (reply,) = await self._require_commander().commander([command])
        if not isinstance(reply, Acknowledge):
            raise DeviceError(f"the Sky Commander did not acknowledge {command.describe()}")

    async def _set_site(self, site: Site) -> None:
        """The box keeps no site: only the PC-side alt/az of the last reading changes."""
        position = self._position
        if position is not None:
            self._position = position.at_site(site)
            self._publish_now()

    async def _abort(self) -> None:
        """Release every arrow; ``U`` ends a GOTO (motors ramp down, UTILITY mode). Written at
        once first (``q``, ``b``, and ``U`` during a GOTO: see ``SkyTrackerLine.stop_at_once``),
        then confirmed in an ordinary turn by reading the status back."""
        line = self._require_line()
        self._cancel_pulses()
        self._held.clear()
        self._loop_presses.clear()
        at_once: list[TrackerCommand] = [ReleaseDirections()]
        if self._mode is TrackerMode.GOTO:
            at_once.append(SelectMode(TrackerMode.UTILITY))
        try:
            await line.stop_at_once(at_once)
        except NotConnectedError as error:  # the confirming turn below says what is wrong
            logger.warning("a stop could not be written at once: %s", error)
        commands: list[TrackerCommand] = [ReleaseDirections()]
        mode = self._mode
        if mode is TrackerMode.GOTO:
            mode = TrackerMode.UTILITY
            commands.append(SelectMode(mode))
        elif self._rest_mode is not None and self._rest_mode is not mode:
            mode = self._rest_mode
            commands.append(SelectMode(mode))
        self._rest_mode = None
        await self._send_confirmed(commands, mode=mode or TrackerMode.UTILITY)
        # The abort is done; a failed read afterwards is only a stale state (named in problems).
        with contextlib.suppress(DeviceError):
            await self.refresh()

    async def _set_tracking(self, mode: TrackingMode) -> None:
        """TRACK (``T``) for sidereal/alt-az tracking; OFF is UTILITY (``U``), motors held."""
        self._require_line()
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                "a GOTO is running and ends in tracking by itself; changing tracking now would "
                "abort it (use abort() to stop it)"
            )
        if self._held or self._pulses:
            raise InvalidValueError("stop moving the axes before changing tracking")
        await self._end_rate_loop()  # custom rates, lunar, solar, King: a PC loop (rates.py)
        target = TrackerMode.UTILITY if mode is TrackingMode.OFF else TrackerMode.TRACK
        if mode is not TrackingMode.OFF:
            self._tracking_choice = mode
        await self._send_confirmed([SelectMode(target)], mode=target)
        self._publish_now()
        try:
            await self._start_rate_loop()
        except LimitError as error:  # tracking is on; the recorded rates would head out
            logger.warning("%s: custom tracking rates not started: %s", self.spec, error)
            self._loop_problems = (f"custom tracking rates not started: {error}",)
            self._publish_now()

    async def standby(self) -> None:
        """``B``: cut the motor drive to save battery (a GOTO is aborted first with ``U``)."""
        self._require_line()
        await self._end_rate_loop()
        self._cancel_pulses()
        self._held.clear()
        commands: list[TrackerCommand] = [ReleaseDirections()]
        if self._mode is TrackerMode.GOTO:
            commands.append(SelectMode(TrackerMode.UTILITY))
        commands.append(SelectMode(TrackerMode.STANDBY))
        self._rest_mode = None
        await self._send_confirmed(commands, mode=TrackerMode.STANDBY)
        self._publish_now()

    async def _move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        """Press the arrow of the nearest supported rate (see motion.py); 0 releases it."""
        self._refuse_during_goto("moving an axis")
        motion = axis_motion(axis, rate_deg_s)
        if motion is not None:
            if axis in self._pulses:
                raise InvalidValueError(f"the {axis.name.lower()} axis is pulse guiding")
            other = self._held.get(_other(axis))
            if other is not None and other.mode is not motion.mode:
                raise InvalidValueError(
                    f"the box moves both axes in one mode: the other axis moves in "
                    f"{other.mode.name}, this rate needs {motion.mode.name}; stop it first"
                )
            if self._pulses and motion.mode is not TrackerMode.GUIDE:
                raise InvalidValueError("a guide pulse is running: wait for it to end")
            self._held[axis] = motion
        else:
            self._held.pop(axis, None)
        await self._apply_buttons()

    async def _pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        """GUIDE mode (``D``) at the ``K`` speed, press the arrow, release after the duration.

        Returns at once; :attr:`MountState.pulse_guiding` is true until the pulse ends.
        """
        self._refuse_during_goto("pulse guiding")
        if self._mode not in BOX_TRACKING:
            raise NotSupportedError(
                "the Sky Tracker guides only while tracking (its arrows slew at 4°/s in UTILITY "
                "mode): start tracking first"
            )
        axis, button = guide_button(direction)
        held = self._held.get(axis)
        if held is not None:
            raise InvalidValueError(f"the {axis.name.lower()} axis is moving: stop it first")
        if any(m.mode is not TrackerMode.GUIDE for m in self._held.values()):
            raise InvalidValueError("an axis moves at a TRACK or UTILITY rate: stop it first")
        if duration_ms == 0:
            return
        previous = self._pulses.pop(axis, None)
        if previous is not None:
            previous[1].cancel()
        task = asyncio.create_task(self._end_pulse(axis, duration_ms / 1000.0))
        self._pulses[axis] = (button, task)
        try:
            await self._apply_buttons()
        except BaseException:
            task.cancel()
            self._pulses.pop(axis, None)
            raise

    async def _end_pulse(self, axis: MountAxis, duration_s: float) -> None:
        await asyncio.sleep(duration_s)
        entry = self._pulses.get(axis)
        if entry is None or entry[1] is not asyncio.current_task():
            return
        del self._pulses[axis]
        try:
            await self._apply_buttons()
        except (MountError, LinkError) as error:
            logger.warning("could not end a guide pulse: %s", error)
            self._problems = (f"could not end a guide pulse: {error}",)
            self._publish_now()

    def _refuse_during_goto(self, what: str) -> None:
        if self._mode is TrackerMode.GOTO:
            raise SlewInProgressError(
                f"a GOTO is running: {what} would abort it (the box ignores arrows during a "
                "GOTO); wait for it to end or abort() it first"
            )

    async def _release_all_buttons(self) -> None:
        self._cancel_pulses()
        if self._held or self._loop_presses or self._loop_on:  # the loop's: even mid-release
            self._held.clear()
            self._loop_presses.clear()
            await self._apply_buttons()

    async def _apply_buttons(self, still: Callable[[], bool] | None = None) -> bool:
        """Send the mode, ``K`` and arrows that the held motions, the custom-rate loop's presses
        and pulses call for, in one turn; with ``still``, only if it holds once the turn is ours
        (False: nothing sent).

        ``b`` releases every arrow, so the arrows still wanted are pressed again after it. A
        pulse on an axis takes it over from the loop for its duration.
        """
        async with self._buttons:
            self._require_line()
            if still is not None and not still():
                return False
            loop = {a: m for a, m in self._loop_presses.items() if a not in self._pulses}
            if self._loop_taken:  # another command took over: the loop's arrows go
                loop.clear()
            pulses = {axis: button for axis, (button, _) in self._pulses.items()}
            if self._loop_on:  # a pulse adds the loop's rate on its axis (rates.py)
                for axis, button in list(pulses.items()):
                    del pulses[axis]
                    combined = self._pulse_with_loop(axis, button)
                    if combined is not None:
                        loop[axis] = combined
            plan = plan_buttons(
                {**loop, **self._held},
                pulses,
                pulse_speeds_arcsec_s=self._pulse_speeds,
                mode=self._mode,
                rest_mode=self._rest_mode,
            )
            self._rest_mode = plan.rest_mode
            commands: list[TrackerCommand] = []
            change_speeds = plan.guide_speeds_arcsec_s != self._guide_speeds
            if change_speeds:
                commands.append(SetGuideSpeed(*plan.guide_speeds_arcsec_s))
            if plan.mode is not self._mode:
                commands.append(SelectMode(plan.mode))
            commands.append(ReleaseDirections())
            commands += [PressDirection(direction) for direction in plan.pressed]
            await self._send_confirmed(
                commands,
                mode=plan.mode,
                pressed=plan.all_pressed,
                speeds=plan.guide_speeds_arcsec_s if change_speeds else None,
            )
            self._publish_now()
            return True
