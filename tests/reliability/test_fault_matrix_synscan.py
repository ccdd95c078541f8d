"""The fault matrix of the SynScan driver: every public command x every fault the emulator injects.

Each cell is a driver connected to its own emulated hand control (over a 9600-baud paced memory
link that the driver reopens through its factory after a ``close``), a fault armed on the
command's key, and the command run once. For every cell:

- the outcome is the one the column promises (answered / recovered transparently / a clear
  ``DeviceError`` naming the cause, followed by recovery once the device answers again);
- the command's result is its own, checked against the simulator behind the emulator, and so are
  the replies of the commands after it (position, site, time read back);
- a failed command leaves the cached coordinates as they were, and ``problems`` names the cause
  where the state is concerned (a poll, an unconfirmed stop);
- after the fault clears, the next command succeeds within one timeout (plus a CPU margin);
- no motion is left behind that the driver does not report: a motion command or stop that failed
  is undone (stopped) as soon as the link works again.

The timeout is short (the driver takes ``timeout_s``); the columns scale with it ("delay within" is
0.1 s, "beyond" is 0.1 s past it). The cells of a column run concurrently (each its own
emulator), so the whole matrix costs about one column's worst cell per column. The table of
outcomes is in ``docs/reliability-faults-synscan.md``.
"""

from __future__ import annotations

import asyncio
import enum
import re
from collections.abc import AsyncIterator, Awaitable, Callable
from contextlib import asynccontextmanager
from dataclasses import dataclass
from datetime import timedelta

import pytest

from scopelink.astro import SIDEREAL_RATE_DEG_S, Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.links import Link
from scopelink.mount import (
    DeviceError,
    GuideDirection,
    Limits,
    MountAxis,
    MountState,
    ParkPosition,
    TrackingMode,
)
from scopelink.servers.faults import Fault, FaultInjector, FaultKind
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import EQ6, SimClock, SimulatedMount
from tests.support.quick_bench import run_bench
from tests.support.synscan_driver import (
    MADRID,
    START,
    Rig,
    assert_position_matches,
    rig,
)

TIMEOUT_S = 1.0
"""Long enough that a loaded machine's scheduling stalls (0.3-0.5 s seen with a column's cells
and other test runs sharing two cores) do not turn a prompt reply into a late one."""
WITHIN_S = 0.1
"""A late or slow reply that still lies well within the timeout."""
BEYOND_S = TIMEOUT_S + 0.1
"""A reply that comes after the driver gave up and has sent its resynchronising echo (the drain
waits 50 ms of quiet), so the echo must tell the stale bytes from its own answer."""
SHORT_TIMEOUT_S = 0.5
"""For the tests outside the matrix, whose outcome does not hang on one reply being prompt."""
MARGIN_S = 3.0
"""Scheduling slack for the time limits on recovery (a connect, a dozen exchanges, has taken
3 s under a load of 6 on two cores; it takes 0.1 s on an idle machine)."""

NAME = "memory hand control"


class Outcome(enum.Enum):
    ANSWERED = "answered"
    """The reply came (late or slowly) within the timeout: no recovery."""
    RECOVERED = "recovered"
    """Resynchronised (and reconnected after a close), the command re-sent, success."""
    FAILS = "fails"
    """A DeviceError naming the cause; the next command after the fault clears recovers."""


@dataclass(frozen=True)
class Column:
    """One fault, as armed on the key of a command whose reply is ``reply_length`` bytes."""

    name: str
    kind: FaultKind
    seconds: Callable[[int], float | None]
    outcome: Callable[[int], Outcome]
    multi_byte_only: bool = False
    """Only commands whose reply has more than one byte: a slow fault cannot touch a one-byte
    reply (``#``), there is no gap between its bytes, so those cells would repeat "no fault"."""

    def fault(self, key: str, reply_length: int) -> Fault:
        return Fault(self.kind, key, seconds=self.seconds(reply_length))


def _always(outcome: Outcome) -> Callable[[int], Outcome]:
    return lambda _length: outcome


def _spread(total_s: float) -> Callable[[int], float | None]:
    """Byte gap that makes a reply of ``length`` bytes take ``total_s`` (slow faults)."""
    return lambda length: total_s / max(length - 1, 1)


COLUMNS = [
    Column("drop", FaultKind.DROP, lambda _n: None, _always(Outcome.RECOVERED)),
    Column("short", FaultKind.SHORT, lambda _n: None, _always(Outcome.RECOVERED)),
    Column("malformed", FaultKind.MALFORMED, lambda _n: None, _always(Outcome.RECOVERED)),
    Column("delay within", FaultKind.DELAY, lambda _n: WITHIN_S, _always(Outcome.ANSWERED)),
    Column("delay beyond", FaultKind.DELAY, lambda _n: BEYOND_S, _always(Outcome.RECOVERED)),
    Column(
        "slow within",
        FaultKind.SLOW,
        _spread(WITHIN_S),
        _always(Outcome.ANSWERED),
        multi_byte_only=True,
    ),
    Column(
        "slow beyond",
        FaultKind.SLOW,
        _spread(BEYOND_S),
        _always(Outcome.RECOVERED),
        multi_byte_only=True,
    ),
    Column("stall", FaultKind.STALL, lambda _n: None, _always(Outcome.FAILS)),
    Column("halt", FaultKind.HALT, lambda _n: None, _always(Outcome.FAILS)),
    Column("close and reopen", FaultKind.CLOSE, lambda _n: None, _always(Outcome.RECOVERED)),
]


# --- the rig ------------------------------------------------------------------------------------


@asynccontextmanager
async def memory_rig(*, connect: bool = True, timeout_s: float = TIMEOUT_S) -> AsyncIterator[Rig]:
    """The driver on a paced memory link to the emulator; the factory opens a new link each
    time, so a ``close`` fault is followed by a transparent reopen (as with a TCP bridge)."""
    # The emulated hand control obeys any sync: near the pole, where this rig points, a 0.5°
    # step turns the RA axis far, which the simulator's own limits.max_sync_deg would refuse.
    sim = SimulatedMount(
        EQ6, site=MADRID, clock=SimClock.stepped(START), limits=Limits(max_sync_deg=180.0)
    )
    async with SynScanEmulator(sim, faults=FaultInjector()) as emulator:

        async def open_memory() -> Link:
            return await emulator.on_memory()

        mount = SynScanMount(
            open_memory, site=MADRID, clock=sim.now, timeout_s=timeout_s, name=NAME
        )
        if connect:
            await mount.connect()
        try:
            yield Rig(mount, sim, emulator, "memory")
        finally:
            await mount.disconnect()


def commanded_rate(sim: SimulatedMount, axis: MountAxis) -> float:
    """The manual rate an axis settles at (after any ramp; 0 when it follows the sky or
    stands), with the stepped clock standing still."""
    motor, later = sim.axes[axis.value], sim.elapsed() + 60.0
    return 0.0 if motor.is_following_at(later) else motor.rate_at(later)


def assert_at_rest(r: Rig) -> None:
    """Nothing moves in the simulator (once a stop's deceleration is over), and the driver does
    not claim otherwise."""
    truth = r.sim.step(10.0)
    assert not truth.slewing, truth
    for axis in MountAxis:
        assert commanded_rate(r.sim, axis) == 0.0, axis
    assert not r.mount.state.slewing, r.mount.state


def same_coordinates(a: MountState, b: MountState) -> bool:
    return (a.read_at, a.ra_j2000_hours, a.dec_j2000_deg, a.alt_deg, a.az_deg) == (
        b.read_at,
        b.ra_j2000_hours,
        b.dec_j2000_deg,
        b.alt_deg,
        b.az_deg,
    )


# --- the commands -------------------------------------------------------------------------------


async def nothing(_r: Rig) -> None:
    return None


async def refresh_then(r: Rig) -> MountState:
    return await r.mount.refresh()


@dataclass(frozen=True)
class Command:
    """One public method of the driver, the key its fault is armed on, and how to check it."""

    name: str
    key: str | None
    """The first byte of the exchange the fault hits; None: the method makes no exchange."""
    reply_length: int
    run: Callable[[Rig], Awaitable[object]]
    verify: Callable[[Rig, object], Awaitable[None]]
    prepare: Callable[[Rig], Awaitable[None]] = nothing
    what: str = ""
    """How the driver names the faulted exchange in errors (``describe()`` of the command)."""
    connected_first: bool = True
    state_problem: bool = False
    """A failure is published in ``state.problems`` (polls and motion)."""
    recover: Callable[[Rig], Awaitable[object]] = refresh_then
    """The next command once the fault has cleared (must succeed within one timeout)."""


async def connect(r: Rig) -> None:
    await r.mount.connect()


async def verify_connected(r: Rig, _result: object) -> None:
    assert r.mount.state.connected
    assert r.mount.identity.model == "EQ6 GOTO"
    assert_position_matches(r.mount.state, r.sim.snapshot())


async def verify_refresh(r: Rig, result: object) -> None:
    assert isinstance(result, MountState)
    assert_position_matches(result, r.sim.snapshot())


GOTO_TARGET = (7.5, 35.0)
ALTAZ_TARGET = (45.0, 120.0)


async def verify_goto_equatorial(r: Rig, _result: object) -> None:
    assert r.mount.state.slewing
    r.sim.step(180.0)
    state = await r.mount.refresh()
    assert not state.slewing
    assert state.ra_j2000_hours == pytest.approx(GOTO_TARGET[0], abs=1e-4)
    assert state.dec_j2000_deg == pytest.approx(GOTO_TARGET[1], abs=1e-3)


async def verify_goto_horizontal(r: Rig, _result: object) -> None:
    r.sim.step(180.0)
    state = await r.mount.refresh()
    assert state.alt_deg == pytest.approx(ALTAZ_TARGET[0], abs=0.01)
    assert state.az_deg == pytest.approx(ALTAZ_TARGET[1], abs=0.01)


async def sync_near(r: Rig) -> None:
    r.mount.syncs_on_device = True  # the driver's own 's' exchange, not a sync kept on the PC
    state = r.mount.state
    assert state.ra_j2000_hours is not None
    assert state.dec_j2000_deg is not None
    await r.mount.sync_equatorial(state.ra_j2000_hours, state.dec_j2000_deg - 0.5)


async def verify_sync(r: Rig, _result: object) -> None:
    truth = r.sim.snapshot()
    assert truth.dec_j2000_deg is not None
    assert truth.dec_j2000_deg == pytest.approx(89.84 - 0.5, abs=0.02)
    assert_position_matches(await r.mount.refresh(), truth)


async def start_goto(r: Rig) -> None:
    await r.mount.goto_equatorial(*GOTO_TARGET)
    assert r.sim.step(1.0).slewing  # mid-slew


async def verify_stopped(r: Rig, _result: object) -> None:
    assert_at_rest(r)


async def start_primary(r: Rig) -> None:
    await r.mount.move_axis(MountAxis.PRIMARY, 1.0)
    assert commanded_rate(r.sim, MountAxis.PRIMARY) == pytest.approx(1.0, abs=1e-3)


async def verify_primary_moves(r: Rig, _result: object) -> None:
    assert commanded_rate(r.sim, MountAxis.PRIMARY) == pytest.approx(1.0, abs=1e-3)
    assert commanded_rate(r.sim, MountAxis.SECONDARY) == 0.0
    assert r.mount.state.slewing


async def verify_primary_stopped(r: Rig, _result: object) -> None:
    assert commanded_rate(r.sim, MountAxis.PRIMARY) == 0.0
    assert not r.mount.state.slewing


FIXED_SPEED = 5  # 64x sidereal


async def verify_fixed_speed(r: Rig, _result: object) -> None:
    rate = commanded_rate(r.sim, MountAxis.SECONDARY)
    assert rate == pytest.approx(64 * SIDEREAL_RATE_DEG_S, rel=0.01)


PULSE_MS = 300


async def verify_pulse(r: Rig, _result: object) -> None:
    # The pulse runs now at the guide rate on Dec, and is ended by the driver's timer.
    assert commanded_rate(r.sim, MountAxis.SECONDARY) != 0.0
    assert r.mount.state.pulse_guiding
    limit_s = PULSE_MS / 1000 + TIMEOUT_S + MARGIN_S
    await r.mount.wait_for(lambda state: not state.pulse_guiding, timeout_s=limit_s)
    assert commanded_rate(r.sim, MountAxis.SECONDARY) == 0.0


async def verify_tracking(r: Rig, _result: object) -> None:
    assert r.sim.tracking is TrackingMode.SIDEREAL
    assert r.mount.state.tracking is TrackingMode.SIDEREAL


PARK = ParkPosition(30.0, 150.0)


async def park(r: Rig) -> None:
    r.mount.park_position = PARK
    await r.mount.park()


async def verify_parked(r: Rig, _result: object) -> None:
    assert r.mount.parking  # on its way: parked once it has arrived (issue #11 part 4)
    r.sim.step(300.0)
    state = await r.mount.refresh()
    assert state.parked
    assert state.alt_deg == pytest.approx(PARK.alt_deg, abs=0.01)
    assert state.az_deg == pytest.approx(PARK.az_deg, abs=0.01)
    assert state.tracking is TrackingMode.OFF


async def verify_unparked(r: Rig, _result: object) -> None:
    assert not r.mount.state.parked


NEW_SITE = Site(41.25, -3.5, elevation_m=650.0)


async def verify_site(r: Rig, _result: object) -> None:
    assert r.sim.site.latitude_deg == pytest.approx(NEW_SITE.latitude_deg, abs=1e-3)
    assert r.sim.site.longitude_deg == pytest.approx(NEW_SITE.longitude_deg, abs=1e-3)
    assert r.mount.site == NEW_SITE


NEW_TIME = START + timedelta(hours=1, minutes=7)


async def verify_time(r: Rig, _result: object) -> None:
    gap = r.emulator.hand_control.now() - NEW_TIME
    assert abs(gap.total_seconds()) <= 1.0


async def verify_read_site(r: Rig, result: object) -> None:
    assert isinstance(result, Site)
    assert result.latitude_deg == pytest.approx(MADRID.latitude_deg, abs=1e-3)
    assert result.longitude_deg == pytest.approx(MADRID.longitude_deg, abs=1e-3)


async def verify_read_time(r: Rig, result: object) -> None:
    assert result == r.sim.now().replace(microsecond=0)


async def verify_disconnected(r: Rig, _result: object) -> None:
    assert not r.mount.state.connected
    assert commanded_rate(r.sim, MountAxis.PRIMARY) == 0.0


async def reconnect(r: Rig) -> None:
    await r.mount.connect()


COMMANDS = [
    Command(
        "connect",
        "V",
        7,
        connect,
        verify_connected,
        what="get hand control version",
        connected_first=False,
        recover=reconnect,
    ),
    Command(
        "refresh",
        "e",
        18,
        refresh_then,
        verify_refresh,
        what="get precise RA/Dec",
        state_problem=True,
    ),
    Command(
        "goto_equatorial",
        "r",
        1,
        lambda r: r.mount.goto_equatorial(*GOTO_TARGET),
        verify_goto_equatorial,
        what="precise goto RA",
        state_problem=True,
    ),
    Command(
        "goto_horizontal",
        "b",
        1,
        lambda r: r.mount.goto_horizontal(*ALTAZ_TARGET),
        verify_goto_horizontal,
        what="precise goto Az",
        state_problem=True,
    ),
    Command("sync_equatorial", "s", 1, sync_near, verify_sync, what="precise sync RA"),
    Command(
        "abort",
        "M",
        1,
        lambda r: r.mount.abort(),
        verify_stopped,
        prepare=start_goto,
        what="cancel goto",
        state_problem=True,
    ),
    Command(
        "move_axis",
        "P",
        1,
        lambda r: r.mount.move_axis(MountAxis.PRIMARY, 1.0),
        verify_primary_moves,
        what="slew RA/Azm + at",
        state_problem=True,
    ),
    Command(
        "move_axis 0 (stop)",
        "P",
        1,
        lambda r: r.mount.move_axis(MountAxis.PRIMARY, 0.0),
        verify_primary_stopped,
        prepare=start_primary,
        what="stop RA/Azm",
        state_problem=True,
    ),
    Command(
        "move_axis_fixed",
        "P",
        1,
        lambda r: r.mount.move_axis_fixed(MountAxis.SECONDARY, FIXED_SPEED),
        verify_fixed_speed,
        what="slew Dec/Alt + at fixed rate",
        state_problem=True,
    ),
    Command(
        "pulse_guide",
        "P",
        1,
        lambda r: r.mount.pulse_guide(GuideDirection.NORTH, PULSE_MS),
        verify_pulse,
        what="slew Dec/Alt + at",
        state_problem=True,
    ),
    Command(
        "set_tracking",
        "T",
        1,
        lambda r: r.mount.set_tracking(TrackingMode.SIDEREAL),
        verify_tracking,
        what="set tracking",
    ),
    Command("park", "b", 1, park, verify_parked, what="precise goto Az", state_problem=True),
    Command("unpark", None, 0, lambda r: r.mount.unpark(), verify_unparked, prepare=park),
    Command(
        "set_site", "W", 1, lambda r: r.mount.set_site(NEW_SITE), verify_site, what="set location"
    ),
    Command("set_time", "H", 1, lambda r: r.mount.set_time(NEW_TIME), verify_time, what="set time"),
    Command(
        "read_site",
        "w",
        9,
        lambda r: r.mount.read_site(),
        verify_read_site,
        what="get location",
    ),
    Command("read_time", "h", 9, lambda r: r.mount.read_time(), verify_read_time, what="get time"),
    Command(
        "disconnect",
        "P",
        1,
        lambda r: r.mount.disconnect(),
        verify_disconnected,
        prepare=start_primary,
        what="stop RA/Azm",
        recover=reconnect,
    ),
]


# --- one cell -----------------------------------------------------------------------------------


def cell_outcome(command: Command, column: Column) -> Outcome:
    if command.key is None:
        return Outcome.ANSWERED  # no exchange: no fault can touch it
    return column.outcome(command.reply_length)


async def probe_the_truth(r: Rig) -> None:
    """The replies after the cell belong to their own commands: position, site and time."""
    state = await r.mount.refresh()
    assert_position_matches(state, r.sim.snapshot())
    assert state.problems == ()
    site = await r.mount.read_site()
    assert site.latitude_deg == pytest.approx(r.sim.site.latitude_deg, abs=1e-3)
    assert await r.mount.read_time() == r.emulator.hand_control.now().replace(microsecond=0)


async def run_cell(command: Command, column: Column) -> None:
    outcome = cell_outcome(command, column)
    loop = asyncio.get_running_loop()
    async with memory_rig(connect=command.connected_first) as r:
        await command.prepare(r)
        statistics = r.mount.wire.statistics
        failures, reconnects = statistics.failures, statistics.reconnects
        before = r.mount.state
        fault = None
        if command.key is not None:
            fault = r.emulator.faults.add(column.fault(command.key, command.reply_length))
        started = loop.time()
        if outcome is Outcome.FAILS:
            await check_failure(r, command, column, before)
            r.emulator.faults.resume()
            started = loop.time()
            await command.recover(r)
            assert loop.time() - started <= TIMEOUT_S + MARGIN_S
            # Whatever the failed command may have started has been stopped again.
            assert_at_rest(r)
        else:
            result = await command.run(r)
            elapsed = loop.time() - started
            fired = [record.fault for record in r.emulator.faults.fired]
            assert fired == ([] if fault is None else [fault])
            # Recovery costs one timeout (or the fault's own delay) beyond the answer.
            assert elapsed <= BEYOND_S + TIMEOUT_S + MARGIN_S
            # Failed exchanges, not resynchronisations: a poll the driver cancels (the horizon
            # guard's poller stops with the motion) resynchronises too, and that is no fault.
            assert statistics.failures - failures == int(outcome is Outcome.RECOVERED)
            reopened = int(column.kind is FaultKind.CLOSE and command.key is not None)
            assert statistics.reconnects - reconnects == reopened + int(command.key == "V")
            await command.verify(r, result)
        if command.name == "disconnect" and not r.mount.state.connected:
            await r.mount.connect()
        await probe_the_truth(r)


async def check_failure(r: Rig, command: Command, column: Column, before: MountState) -> None:
    """The command fails with an error naming the cause; the cache keeps the last good reading."""
    if command.name == "disconnect":
        # Disconnect always lets go of the link; the stop it could not send stays owed.
        await r.mount.disconnect()
        assert not r.mount.state.connected
        # Disconnected: no motion state is claimed (issue #11.6); the problem says it may turn.
        assert not r.mount.state.slewing
        assert "not confirmed" in r.mount.state.problems[0]
        assert commanded_rate(r.sim, MountAxis.PRIMARY) != 0.0
        return
    with pytest.raises(DeviceError) as raised:
        await command.run(r)
    message = str(raised.value)
    cause = rf"no reply to '{re.escape(command.what)}.*' within {TIMEOUT_S:g} s on {NAME}"
    assert re.search(cause, message), message
    assert "resynchronising failed" in message, message
    assert "is the hand control switched on" in message, message
    state = r.mount.state
    if command.connected_first:
        assert same_coordinates(state, before)
    if command.state_problem:
        assert state.problems, state
        assert f"within {TIMEOUT_S:g} s" in state.problems[0], state.problems
        if command.key != "e":  # a motion command: its undoing stop is owed, and shown
            assert "not confirmed" in state.problems[0], state.problems
            assert state.slewing
    if column.kind is FaultKind.STALL:
        assert r.emulator.faults.stalled
    else:
        assert r.emulator.faults.halted


def _by_name(*names: str) -> tuple[Column, ...]:
    return tuple(column for column in COLUMNS if column.name in names)


COLUMN_GROUPS = [
    # Paired so that each test waits about as long as its slowest cell. The slow faults go
    # together and only with the light multi-byte cells: a slow reply sleeps between its bytes,
    # and each sleep also waits for whatever CPU work other cells do (a goto costs the simulator
    # 0.2 s), so beside the heavy cells a reply "within" the timeout could turn late.
    _by_name("stall", "halt"),
    _by_name("drop", "short"),
    _by_name("delay within", "delay beyond"),
    _by_name("slow within", "slow beyond"),
    _by_name("malformed", "close and reopen"),
]
assert sorted(c.name for group in COLUMN_GROUPS for c in group) == sorted(c.name for c in COLUMNS)


@pytest.mark.solo
@pytest.mark.parametrize(
    "columns", COLUMN_GROUPS, ids=[" + ".join(c.name for c in group) for group in COLUMN_GROUPS]
)
async def test_every_command_under_each_fault(columns: tuple[Column, ...]) -> None:
    """All commands under these faults, concurrently (each cell with its own emulator)."""
    cells = [
        (command, column)
        for column in columns
        for command in COMMANDS
        if command.reply_length > 1 or not column.multi_byte_only
    ]
    results = await asyncio.gather(
        *(run_cell(command, column) for command, column in cells), return_exceptions=True
    )
    failures = [
        f"{command.name} x {column.name}: {type(result).__name__}: {result}"
        for (command, column), result in zip(cells, results, strict=True)
        if isinstance(result, BaseException)
    ]
    assert not failures, "\n".join(failures)


CONNECT_KEYS = ["K", "V", "m", "P", "J", "w", "L", "e", "t", "p"]
"""Every exchange of ``connect``: echo, identification, then the first full state read."""


async def test_connect_recovers_from_a_lost_reply_at_every_step() -> None:
    async def lose_one(key: str) -> None:
        async with memory_rig(connect=False) as r:
            fault = r.emulator.faults.add(Fault(FaultKind.DROP, key))
            await r.mount.connect()
            assert [record.fault for record in r.emulator.faults.fired] == [fault]
            # The opening echo is checked once more by connect itself; any later reply is
            # recovered by the wire: either way one more resynchronisation than the opening one.
            assert r.mount.wire.statistics.resyncs == 2
            assert r.mount.wire.statistics.failures == int(key != "K")
            await verify_connected(r, None)
            await probe_the_truth(r)

    results = await asyncio.gather(*map(lose_one, CONNECT_KEYS), return_exceptions=True)
    failures = [
        f"drop on {key!r}: {result!r}"
        for key, result in zip(CONNECT_KEYS, results, strict=True)
        if isinstance(result, BaseException)
    ]
    assert not failures, "\n".join(failures)


# --- real transports, and a link that breaks during motion ----------------------------------------


async def test_a_tcp_bridge_that_closes_during_a_goto_is_reopened_transparently() -> None:
    async with rig("tcp", timeout_s=TIMEOUT_S) as r:
        r.emulator.faults.add(Fault(FaultKind.CLOSE, "r"))
        await r.mount.goto_equatorial(*GOTO_TARGET)
        assert r.mount.wire.statistics.reconnects == 2  # connect, then after the close
        await verify_goto_equatorial(r, None)
        await probe_the_truth(r)


async def test_a_pty_that_closes_while_an_axis_turns_is_a_clear_error_and_says_so() -> None:
    """A serial port whose device end is gone cannot be reopened: the stop cannot reach the
    mount, the error says the link closed, and the state's problem says the mount may move."""
    async with rig("pty", timeout_s=TIMEOUT_S) as r:
        await start_primary(r)
        good = r.mount.state
        r.emulator.faults.add(Fault(FaultKind.CLOSE, "P"))
        with pytest.raises(DeviceError, match=r"closed during 'stop RA/Azm.*, and cannot open"):
            await r.mount.move_axis(MountAxis.PRIMARY, 0.0)
        state = r.mount.state
        assert same_coordinates(state, good)
        assert state.slewing
        assert "stop of the primary axis not confirmed" in state.problems[0]
        assert commanded_rate(r.sim, MountAxis.PRIMARY) == pytest.approx(1.0, abs=1e-3)
        with pytest.raises(DeviceError, match="cannot open"):
            await r.mount.refresh()  # still owed, still nothing to send it on
        # The link is lost now: no motion state is claimed (issue #11.6), the problem says why.
        assert not r.mount.state.connected
        assert not r.mount.state.slewing
        assert "stop of the primary axis not confirmed" in r.mount.state.problems[0]


async def test_the_poller_stops_a_motion_whose_stop_was_lost_as_soon_as_the_link_returns() -> None:
    """Serve's situation: a client's stop fails on a hung link; nobody repeats it, but the state
    poller's first exchange after the link returns carries the owed stop."""
    async with memory_rig(timeout_s=SHORT_TIMEOUT_S) as r, r.mount.watching():
        await start_primary(r)
        r.emulator.faults.add(Fault(FaultKind.STALL, "P"))
        with pytest.raises(DeviceError, match=r"no reply to 'stop RA/Azm"):
            await r.mount.move_axis(MountAxis.PRIMARY, 0.0)
        assert r.mount.state.slewing
        assert commanded_rate(r.sim, MountAxis.PRIMARY) != 0.0  # the stop never arrived
        r.emulator.faults.resume()
        loop = asyncio.get_running_loop()
        resumed = loop.time()
        limit_s = SHORT_TIMEOUT_S + MARGIN_S
        await r.mount.wait_for(lambda state: not state.slewing, timeout_s=limit_s)
        assert loop.time() - resumed <= limit_s
        assert commanded_rate(r.sim, MountAxis.PRIMARY) == 0.0
        assert r.mount.state.problems == ()


async def test_a_rate_motion_that_ran_blind_through_an_outage_is_stopped_when_it_ends() -> None:
    """Nobody sent a stop, but the position could not be read while an axis turned: the driver
    stops the axis when the link returns (a goto would carry on: its target was checked)."""
    async with memory_rig(timeout_s=SHORT_TIMEOUT_S) as r:
        await start_primary(r)
        r.emulator.faults.add(Fault(FaultKind.STALL, "e"))
        with pytest.raises(DeviceError, match=r"no reply to 'get precise RA/Dec'"):
            await r.mount.refresh()
        state = r.mount.state
        assert state.slewing
        assert "stop of the primary axis not confirmed" in state.problems[0], state.problems
        assert "the position cannot be read while it turns" in state.problems[0]
        r.emulator.faults.resume()
        assert not (await r.mount.refresh()).slewing
        assert commanded_rate(r.sim, MountAxis.PRIMARY) == 0.0
        await probe_the_truth(r)


async def test_a_guide_pulse_whose_end_is_lost_is_ended_when_the_link_returns() -> None:
    async with memory_rig(timeout_s=SHORT_TIMEOUT_S) as r:
        await r.mount.pulse_guide(GuideDirection.NORTH, PULSE_MS)
        assert commanded_rate(r.sim, MountAxis.SECONDARY) != 0.0
        r.emulator.faults.add(Fault(FaultKind.HALT, "P"))  # the pulse's stop is lost
        limit_s = PULSE_MS / 1000 + 2 * SHORT_TIMEOUT_S + MARGIN_S
        state = await r.mount.wait_for(lambda state: not state.pulse_guiding, timeout_s=limit_s)
        assert commanded_rate(r.sim, MountAxis.SECONDARY) != 0.0  # still turning
        assert state.slewing
        assert any("secondary axis not confirmed" in problem for problem in state.problems)
        r.emulator.faults.resume()
        await r.mount.refresh()  # the next exchange sends the owed stop first
        assert commanded_rate(r.sim, MountAxis.SECONDARY) == 0.0
        assert not r.mount.state.slewing
        await probe_the_truth(r)


async def test_a_device_that_keeps_answering_garbage_is_named_as_such() -> None:
    """Garbage twice (the reply and the re-sent command's): the error says malformed reply, the
    state keeps the last good position and names it; the next poll reads the truth."""
    async with memory_rig(timeout_s=SHORT_TIMEOUT_S) as r:
        good = r.mount.state
        r.emulator.faults.add(Fault(FaultKind.MALFORMED, "e", times=2))
        with pytest.raises(DeviceError) as raised:
            await r.mount.refresh()
        message = str(raised.value)
        assert message.startswith(f"malformed reply on {NAME}: "), message
        assert f"; after recovering, again: malformed reply on {NAME}" in message, message
        assert same_coordinates(r.mount.state, good)
        assert r.mount.state.problems[0].startswith("malformed reply")
        await probe_the_truth(r)


async def test_a_time_re_sent_after_a_fault_is_moved_on_by_the_time_the_retry_took() -> None:
    """A retried ``H`` would set the hand control's clock one timeout behind: the driver sends
    it once more with the time it is by then (the clock running in real time here)."""
    timeout_s = 1.5  # the lag a plain retry leaves must exceed the clock's 1 s resolution
    async with rig("tcp", timeout_s=timeout_s, clock=SimClock.accelerated(1.0, START)) as r:
        r.emulator.faults.add(Fault(FaultKind.DROP, "H"))
        await r.mount.set_time(r.sim.now())
        assert [record.command for record in r.emulator.faults.fired] == ["H"]
        gap = r.emulator.hand_control.now() - r.sim.now()
        assert abs(gap.total_seconds()) <= 1.0, gap


def test_the_fault_recovery_benchmark_runs_and_prints_its_tables() -> None:
    """A tiny run of ``bench.fault_recovery_synscan`` (so the benchmark code cannot rot); it exits
    on a wrong position or a motion left running."""
    result = run_bench("bench.fault_recovery_synscan", "--timeout", "0.3", timeout_s=60)
    printed = result.stdout.splitlines()
    assert printed[0].startswith("date "), printed[0]  # provenance first (bench/provenance.py)
    (title,) = [n for n, line in enumerate(printed) if line.startswith("SynScan driver fault")]
    lines = printed[title:]
    assert lines[0].startswith("SynScan driver fault recovery, timeout 0.3 s")
    cases = lines.index("", 2) - 2  # one row per case, then a blank line
    rows = {line[:22].strip(): line.split() for line in lines[2 : 2 + cases]}
    assert rows["no fault"][2] == "answered"
    assert rows["stall"][1] == "error"
    assert rows["close and reopen"][3] == "recovered"
    assert any(line.startswith("halt") and "x timeout" in line for line in lines)
