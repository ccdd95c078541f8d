"""A synchronous facade over any :class:`Mount`, for scripts and notebooks.

The mount lives on an event loop in a background thread; each call here runs the matching
coroutine there and waits for it. Usage::

    with BlockingMount(SynScanMount("/dev/ttyUSB0", site=site)) as mount:
        mount.goto_object("M31")
        mount.wait_for_slew(timeout_s=120)
        print(mount.state.ra_j2000_hours)

Ctrl-C while waiting cancels the coroutine on the loop (an interrupted ``wait_for_slew`` does
not stop the slew: call :meth:`abort` for that).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Callable, Coroutine, Iterator
from contextlib import contextmanager
from datetime import datetime
from types import TracebackType
from typing import Any, Self, TypeVar

from scopelink.astro import Site
from scopelink.astro.catalog import CatalogObject
from scopelink.mount.base import Mount
from scopelink.mount.limits import Limits
from scopelink.mount.parking import Resume
from scopelink.mount.types import (
    Capabilities,
    GuideDirection,
    Identity,
    MountAxis,
    MountState,
    SlewProgress,
    SlewTarget,
    TrackingMode,
)

__all__ = ["BlockingMount"]

T = TypeVar("T")


class BlockingMount:
    """Blocking calls on ``mount``, whose coroutines run on a private event-loop thread."""

    def __init__(self, mount: Mount) -> None:
        self.mount = mount
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self._loop.run_forever, name="scopelink mount loop", daemon=True
        )
        self._thread.start()

    def _run(self, coroutine: Coroutine[Any, Any, T], timeout_s: float | None = None) -> T:
        if self._loop.is_closed():
            coroutine.close()
            raise RuntimeError("this BlockingMount has been closed")
        future = asyncio.run_coroutine_threadsafe(coroutine, self._loop)
        try:
            return future.result(timeout_s)
        except (KeyboardInterrupt, concurrent.futures.TimeoutError):
            future.cancel()
            raise

    # --- lifetime -------------------------------------------------------------------------------

    def connect(self) -> None:
        self._run(self.mount.connect())

    def disconnect(self) -> None:
        self._run(self.mount.disconnect())

    def close(self) -> None:
        """Disconnect if connected, then stop the loop thread."""
        if self._loop.is_closed():
            return
        try:
            if self.mount.state.connected:
                self.disconnect()
        finally:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join()
            self._loop.close()

    def __enter__(self) -> Self:
        self.connect()
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()

    # --- reads (from the cache: never wait on the wire) -------------------------------------------

    @property
    def state(self) -> MountState:
        return self.mount.state

    @property
    def capabilities(self) -> Capabilities:
        return self.mount.capabilities

    @property
    def identity(self) -> Identity:
        return self.mount.identity

    @property
    def site(self) -> Site:
        return self.mount.site

    @property
    def limits(self) -> Limits:
        return self.mount.limits

    @property
    def target(self) -> SlewTarget | None:
        return self.mount.target

    def now(self) -> datetime:
        return self.mount.now()

    def refresh(self) -> MountState:
        """Read the device now."""
        return self._run(self.mount.refresh())

    @contextmanager
    def watching(self) -> Iterator[None]:
        """Keep :attr:`state` fresh in the background inside ``with``."""
        entered = threading.Event()
        release: asyncio.Event | None = None

        async def hold() -> None:
            nonlocal release
            release = asyncio.Event()
            async with self.mount.watching():
                entered.set()
                await release.wait()

        future = asyncio.run_coroutine_threadsafe(hold(), self._loop)
        entered.wait()
        try:
            yield
        finally:
            assert release is not None
            self._loop.call_soon_threadsafe(release.set)
            future.result()

    def wait_for(
        self, predicate: Callable[[MountState], bool], timeout_s: float | None = None
    ) -> MountState:
        return self._run(self.mount.wait_for(predicate, timeout_s))

    def wait_for_slew(
        self,
        timeout_s: float | None = None,
        progress: Callable[[SlewProgress], None] | None = None,
    ) -> MountState:
        """Block until the slew ends; ``progress`` runs on the loop thread (keep it short)."""
        return self._run(self.mount.wait_for_slew(timeout_s, progress))

    # --- commands -------------------------------------------------------------------------------

    def goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        self._run(self.mount.goto_equatorial(ra_j2000_hours, dec_j2000_deg))

    def goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        self._run(self.mount.goto_horizontal(alt_deg, az_deg))

    def goto_object(self, name: str) -> CatalogObject:
        return self._run(self.mount.goto_object(name))

    def sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        self._run(self.mount.sync_equatorial(ra_j2000_hours, dec_j2000_deg))

    def abort(self) -> None:
        self._run(self.mount.abort())

    def move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        self._run(self.mount.move_axis(axis, rate_deg_s))

    def pulse_guide(self, direction: GuideDirection, duration_ms: int) -> None:
        self._run(self.mount.pulse_guide(direction, duration_ms))

    def set_tracking(self, mode: TrackingMode) -> None:
        self._run(self.mount.set_tracking(mode))

    def park(self) -> None:
        self._run(self.mount.park())

    def unpark(self) -> Resume:
        return self._run(self.mount.unpark())

    def set_site(self, site: Site) -> None:
        self._run(self.mount.set_site(site))

    def set_time(self, utc: datetime) -> None:
        self._run(self.mount.set_time(utc))
