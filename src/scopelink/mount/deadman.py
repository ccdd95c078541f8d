"""The dead-man: a rate motion whose client has gone is stopped.

Front ends that hold a connection per client (LX200, the SynScan server, Stellarium, the
dashboard's page) run each client inside ``Mount.motion_client``: a :class:`MotionClient` is the
owner of the rate motions it starts, and those still running (and changed by nobody since) when
its block ends are stopped. Requests that arrive apart from their client's connection (the
dashboard's HTTP calls) name it by its token inside ``Mount.acting_for``. Who owns which motion is
the horizon guard's record (:meth:`HorizonGuard.axes_of`); this module knows only clients.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import secrets
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from contextlib import asynccontextmanager, contextmanager
from contextvars import ContextVar

from scopelink.mount.errors import MountError
from scopelink.mount.types import MountAxis

__all__ = ["DeadMan", "MotionClient", "current_client"]

logger = logging.getLogger(__name__)


class MotionClient:
    """One client of a front end (an LX200 connection, a dashboard page): the owner of the rate
    motions it starts. ``token`` names it in requests that arrive apart from its connection."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.token = secrets.token_urlsafe(12)

    def __repr__(self) -> str:
        return f"MotionClient({self.name!r})"


_acting_for: ContextVar[MotionClient | None] = ContextVar("scopelink_motion_client", default=None)
"""The client on whose behalf the current task moves the mount (None: nobody in particular)."""


def current_client() -> MotionClient | None:
    """The client on whose behalf the current task moves the mount, if any."""
    return _acting_for.get()


class DeadMan:
    """The clients of one mount. ``axes_of`` tells which axes a client's rate motions turn;
    ``stop_axis`` stops one (through the mount's checked ``move_axis(axis, 0)``)."""

    def __init__(
        self,
        axes_of: Callable[[MotionClient], list[MountAxis]],
        stop_axis: Callable[[MountAxis], Awaitable[None]],
    ) -> None:
        self._axes_of = axes_of
        self._stop_axis = stop_axis
        self.left: Callable[[MotionClient], Awaitable[None]] | None = None
        """Told of every client that leaves, after its motions are stopped (the mount's
        custom tracking rates go back to zero: :class:`scopelink.mount.rates.RateKeeper`)."""
        self._clients: dict[str, MotionClient] = {}

    @asynccontextmanager
    async def client(self, name: str) -> AsyncIterator[MotionClient]:
        """Run a front end's client inside: rate motions it starts are stopped when it goes."""
        client = MotionClient(name)
        self._clients[client.token] = client
        reset = _acting_for.set(client)
        try:
            yield client
        finally:
            with contextlib.suppress(ValueError):  # left from another context: nothing to reset
                _acting_for.reset(reset)
            del self._clients[client.token]
            await self.stop_motions_of(client)

    @contextmanager
    def acting_for(self, token: str | None) -> Iterator[MotionClient | None]:
        """Commands inside are on behalf of the client ``token`` names (if it is still here)."""
        client = self._clients.get(token) if token else None
        reset = _acting_for.set(client)
        try:
            yield client
        finally:
            _acting_for.reset(reset)

    async def stop_motions_of(self, client: MotionClient) -> None:
        """Stop the rate motions ``client`` started that nobody has changed since."""
        for axis in self._axes_of(client):
            logger.warning(
                "%s went away while moving the %s axis: stopping it",
                client.name,
                axis.name.lower(),
            )
            try:
                await asyncio.shield(self._stop_axis(axis))
            except MountError as error:
                logger.warning("stopping the %s axis failed: %s", axis.name.lower(), error)
        if self.left is not None:
            try:
                await asyncio.shield(self.left(client))
            except MountError as error:
                logger.warning("after %s went away: %s", client.name, error)
