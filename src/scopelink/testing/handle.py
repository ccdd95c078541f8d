"""An emulator on its own event-loop thread, for synchronous and asyncio tests alike.

:class:`EmulatorHandle` starts one emulator (:class:`~scopelink.testing.options.EmulatorSpec`) on a
thread running ``links.precise_event_loop()`` (as ``scopelink emulate``), says where clients
connect, and reads its state on that thread. Nothing it offers blocks for longer than the
emulator's loop takes to compute a snapshot, so an asyncio test may call it from its own loop.
See docs/testing-with-scopelink.md.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import shutil
import tempfile
import threading
from collections.abc import Awaitable, Callable
from concurrent.futures import Future
from pathlib import Path
from types import TracebackType
from typing import Any, Self, TypeVar

from scopelink.links import Link, precise_event_loop
from scopelink.mount import MountState, TrackingMode
from scopelink.protocol.skytracker import TrackerMode
from scopelink.protocol.synscan import AnyCommand
from scopelink.servers.faults import Fault, FaultInjector
from scopelink.servers.hosting import HostedDevice
from scopelink.servers.ready import announcement
from scopelink.servers.skytracker import SkyTrackerEmulator
from scopelink.servers.synscan import SynScanEmulator
from scopelink.sim import SimulatedMount
from scopelink.testing.options import Built, Device, EmulatorSpec, build
from scopelink.testing.recording import CommandLog, Received, record_reads

__all__ = [
    "CALL_TIMEOUT_S",
    "START_TIMEOUT_S",
    "STOP_TIMEOUT_S",
    "TASK_GRACE_S",
    "EmulatorHandle",
]

logger = logging.getLogger(__name__)

START_TIMEOUT_S = 30.0
"""How long :meth:`EmulatorHandle.start` waits for the emulator to listen (a loaded CI machine)."""

STOP_TIMEOUT_S = 10.0
"""How long :meth:`EmulatorHandle.close` waits for the emulator's thread to end."""

CALL_TIMEOUT_S = 10.0
"""How long :meth:`EmulatorHandle.call` waits for its function on the emulator's loop."""

TASK_GRACE_S = 1.0
"""How long the tasks still running once the device stopped and its mount was switched off (the
mount's meridian watch ends within 0.25 s) may take to end before they count as stray."""

_T = TypeVar("_T")


class EmulatorHandle:
    """One emulator on its own thread: a context manager (``with`` or ``async with``).

    ``EmulatorHandle(EmulatorSpec(device="synscan", model="EQ6"))``, or keywords:
    ``EmulatorHandle(device="skytracker", transport="pty")``. Once started: :attr:`host`,
    :attr:`port`, :attr:`path`, :attr:`url`, :attr:`device_string`, :attr:`serial_url`,
    :attr:`info`; :meth:`state`, :attr:`position`, :attr:`altaz`, :attr:`tracking`,
    :attr:`mode`; :attr:`log` (what it received); :meth:`advance` (the stepped clock),
    :meth:`inject` (faults); :meth:`call` runs a function on the emulator's loop.
    """

    def __init__(self, spec: EmulatorSpec | None = None, **options: Any) -> None:
        self.spec = spec if spec is not None else EmulatorSpec(**options)
        if spec is not None and options:
            raise TypeError("give an EmulatorSpec or keywords, not both")
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._started = threading.Event()
        self._error: BaseException | None = None
        self._built: Built | None = None
        self._scratch: Path | None = None
        self.stray_tasks: list[str] = []
        """Tasks that had not ended :data:`TASK_GRACE_S` after the device stopped (then
        cancelled); empty unless something in the emulator leaks a task."""
        self.info: dict[str, object] = {}
        """Where and what, as ``scopelink emulate --ready-json`` prints it (once started)."""
        self.log = CommandLog(self._elapsed)
        """Every chunk the emulated device read, with its simulated time."""

    # --- life -----------------------------------------------------------------------------------

    def start(self) -> Self:
        """Start the emulator's thread and return once it listens; raises what stopped it."""
        if self._thread is not None:
            raise RuntimeError("this emulator handle was already started")
        if self.spec.device != "synscan" and self.spec.data_dir is None:
            self._scratch = Path(tempfile.mkdtemp(prefix=f"scopelink-{self.spec.device}-"))
        self._thread = threading.Thread(
            target=self._run, name=f"scopelink {self.spec.device} emulator", daemon=True
        )
        self._thread.start()
        if not self._started.wait(START_TIMEOUT_S):
            self.close()
            raise TimeoutError(f"the {self.spec.device} emulator did not start in time")
        if self._error is not None:
            error, self._error = self._error, None
            self.close()
            raise error
        return self

    def close(self) -> None:
        """Stop the emulator: close its clients and listener, end its loop and thread. Raises
        what ended it if it failed on its own while serving."""
        thread, loop, stop = self._thread, self._loop, self._stop
        if thread is not None and thread.is_alive() and loop is not None and stop is not None:
            with contextlib.suppress(RuntimeError):  # the loop is already closed
                loop.call_soon_threadsafe(stop.set)
            thread.join(STOP_TIMEOUT_S)
            if thread.is_alive():
                raise RuntimeError(f"the {self.spec.device} emulator did not stop in time")
        if self._scratch is not None:
            shutil.rmtree(self._scratch, ignore_errors=True)
            self._scratch = None
        if self._error is not None:  # it stopped on its own, on this error, while serving
            error, self._error = self._error, None
            raise RuntimeError(f"the {self.spec.device} emulator failed: {error!r}") from error

    def __enter__(self) -> Self:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    async def __aenter__(self) -> Self:
        return await asyncio.to_thread(self.start)

    async def __aexit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        await asyncio.to_thread(self.close)

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive() and self._error is None

    def _run(self) -> None:
        with asyncio.Runner(loop_factory=precise_event_loop) as runner:
            try:
                runner.run(self._main())
            except BaseException as error:  # handed to start(), which raises it in the test
                self._error = error
            finally:
                self._started.set()

    async def _main(self) -> None:
        self._loop = asyncio.get_running_loop()
        self._stop = asyncio.Event()
        data_dir = self.data_dir
        self._built = built = build(self.spec, data_dir)
        device = built.device
        serve = device.server.serve if isinstance(device, SynScanEmulator) else device.serve

        async def recorded(link: Link) -> None:
            record_reads(link, self.log)
            await serve(link)

        host = HostedDevice(recorded, wire=built.wire, access=device.access)
        async with device, host:
            if self.spec.transport == "pty":
                await host.on_pty()
            else:
                await host.on_tcp("127.0.0.1", 0)
            self.info = announcement(self.spec.device, device, host.address)
            self._started.set()
            await self._stop.wait()
        await built.mount.disconnect()  # switched off: the motors stop, the mount's watchers end
        current = asyncio.current_task()
        others = [task for task in asyncio.all_tasks() if task is not current]
        if others:
            _, pending = await asyncio.wait(others, timeout=TASK_GRACE_S)
            self.stray_tasks = sorted(task.get_name() for task in pending)
            for task in pending:
                task.cancel()
            await asyncio.gather(*pending, return_exceptions=True)
        if self.stray_tasks:
            logger.warning("tasks left on the emulator's loop (cancelled): %s", self.stray_tasks)

    # --- where ----------------------------------------------------------------------------------

    @property
    def address(self) -> str:
        """``HOST:PORT`` or the pty's path."""
        found = self.info.get("tcp", self.info.get("pty"))
        if not isinstance(found, str):
            raise RuntimeError("the emulator is not started")
        return found

    @property
    def host(self) -> str:
        return self.address.rsplit(":", 1)[0] if "tcp" in self.info else ""

    @property
    def port(self) -> int:
        return int(self.address.rsplit(":", 1)[1]) if "tcp" in self.info else 0

    @property
    def path(self) -> str:
        """The pty a client opens (``""`` over TCP)."""
        return self.address if "pty" in self.info else ""

    @property
    def url(self) -> str:
        """A scopelink link string: ``tcp://127.0.0.1:PORT`` or the pty's path."""
        return f"tcp://{self.address}" if "tcp" in self.info else self.address

    @property
    def device_string(self) -> str:
        """What ``--device`` and :func:`scopelink.drivers.open_mount` take:
        ``synscan:tcp://127.0.0.1:PORT``."""
        return f"{self.spec.device}:{self.url}"

    @property
    def serial_url(self) -> str:
        """What pyserial's ``serial_for_url`` opens: ``socket://127.0.0.1:PORT`` or the pty."""
        return f"socket://{self.address}" if "tcp" in self.info else self.address

    @property
    def data_dir(self) -> Path:
        """The Sky Tracker's and Sky Commander's memory: ``data_dir`` or the temporary one."""
        return self.spec.data_dir or self._scratch or Path()

    # --- state ----------------------------------------------------------------------------------

    @property
    def emulator(self) -> Device:
        """The emulated device itself; touch it only through :meth:`call` (it lives on the
        emulator's thread)."""
        return self._started_parts().device

    @property
    def mount(self) -> SimulatedMount:
        """The simulated mount behind the device (read it through :meth:`call`)."""
        return self._started_parts().mount

    def _started_parts(self) -> Built:
        if self._built is None:
            raise RuntimeError("the emulator is not started")
        return self._built

    def call(self, function: Callable[[], _T | Awaitable[_T]]) -> _T:
        """Run ``function`` on the emulator's loop and return its result (awaited if it is a
        coroutine), waiting at most :data:`CALL_TIMEOUT_S` (then ``TimeoutError``). Not from the
        emulator's own thread (call the function directly there)."""
        loop = self._loop
        if loop is None or not self.running:
            raise RuntimeError("the emulator is not running")

        async def run() -> _T:
            result = function()
            if isinstance(result, Awaitable):
                return await result
            return result

        if threading.current_thread() is self._thread:
            raise RuntimeError("call() from the emulator's own thread: call the function directly")
        future: Future[_T] = asyncio.run_coroutine_threadsafe(run(), loop)
        return future.result(CALL_TIMEOUT_S)

    def state(self) -> MountState:
        """The simulated mount's state now (position, slewing, tracking, parked...)."""
        return self.call(self.mount.snapshot)

    @property
    def position(self) -> tuple[float, float]:
        """Where the mount points now: J2000 (RA hours, Dec degrees)."""
        state = self.state()
        return _known(state.ra_j2000_hours), _known(state.dec_j2000_deg)

    @property
    def altaz(self) -> tuple[float, float]:
        """Where the mount points now: observed (altitude, azimuth) in degrees."""
        state = self.state()
        return _known(state.alt_deg), _known(state.az_deg)

    @property
    def tracking(self) -> TrackingMode:
        return self.state().tracking

    @property
    def mode(self) -> TrackerMode | None:
        """The Sky Tracker's mode (UTILITY, TRACK, GUIDE, STANDBY, GOTO); None for the others."""
        device = self.emulator
        if isinstance(device, SkyTrackerEmulator):
            return self.call(lambda: device.tracker.mode)
        return None

    @property
    def received(self) -> bytes:
        """Every byte the device read so far (:attr:`log` has them chunk by chunk, timed)."""
        return self.log.received

    @property
    def chunks(self) -> list[Received]:
        return self.log.chunks

    def commands(self) -> list[AnyCommand]:
        """The SynScan commands received so far, typed (SynScan hand control only)."""
        if self.spec.device != "synscan":
            raise TypeError(f"commands() reads SynScan; the {self.spec.device}'s are in .received")
        return self.log.synscan_commands()

    # --- changing it ----------------------------------------------------------------------------

    def advance(self, seconds: float) -> None:
        """Move simulated time on by ``seconds`` (a stepped clock moves only so)."""
        self.call(lambda: self.mount.clock.advance(seconds))

    def inject(self, *rules: str | Fault) -> None:
        """Add fault rules (``"e:drop"``, as ``--fault`` takes them) from now on."""
        parsed = [rule if isinstance(rule, Fault) else Fault.parse(rule) for rule in rules]

        def add() -> None:
            for rule in parsed:
                self.faults.add(rule)

        self.call(add)

    @property
    def faults(self) -> FaultInjector:
        """The device's fault injector (``fired`` says what fired); change it via :meth:`call`."""
        return self.emulator.faults

    def _elapsed(self) -> float:
        return self._built.mount.clock.elapsed() if self._built is not None else 0.0


def _known(value: float | None) -> float:
    if value is None:  # a simulated mount always knows where it points
        raise RuntimeError("the simulated mount has no reading")
    return value
