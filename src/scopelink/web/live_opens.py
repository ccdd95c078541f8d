"""How often the dashboard's live connection (``/ws``) may be opened, under an access policy
(``docs/dashboard.md``, "Security", "Limits").

Each open costs the server a hello (the mount, the state, the sky: ~15 kB, a few ms of CPU, a
dead-man client): 16 connections from one address opening and closing it back to back took the
SynScan poller from 42 to 5 polls/s, although every request was within the policy's rate. A page
opens it once and reconnects with a back-off of 0.5 s doubling to 10 s, so these bounds never
touch a page; beyond them the upgrade is answered ``429`` with ``Retry-After``.
"""

from __future__ import annotations

import math
import time
from typing import Final

from scopelink.servers.buckets import KeyedBuckets, TokenBucket

__all__ = [
    "LIVE_OPENS_PER_S",
    "LIVE_OPEN_BURST",
    "LIVE_SERVER_OPENS_PER_S",
    "LIVE_SERVER_OPEN_BURST",
    "LiveOpens",
]

LIVE_OPENS_PER_S: Final = 1.0
"""Live connections one client address may open per second, sustained."""
LIVE_OPEN_BURST: Final = 8
"""... and at once (several tabs, a reload or two)."""
LIVE_SERVER_OPENS_PER_S: Final = 5.0
"""Live connections all clients together may open per second, sustained."""
LIVE_SERVER_OPEN_BURST: Final = 20
_KEPT_ADDRESSES: Final = 1024
"""Addresses whose bucket is kept; beyond, the buckets that have refilled are forgotten."""


class LiveOpens:
    """The token buckets of the opens, per client address and for the server."""

    def __init__(self) -> None:
        self._server = TokenBucket(
            LIVE_SERVER_OPENS_PER_S, LIVE_SERVER_OPEN_BURST, time.monotonic()
        )
        self._addresses = KeyedBuckets(LIVE_OPENS_PER_S, LIVE_OPEN_BURST, _KEPT_ADDRESSES)

    def admit(self, address: str | None) -> float | None:
        """None when an open from ``address`` may go ahead (its tokens taken), else the seconds
        until it may."""
        now = time.monotonic()
        bucket = self._addresses.of(address or "", now)
        wait = max(bucket.wait_for_one(now), self._server.wait_for_one(now))
        if wait > 0.0:
            return max(1.0, math.ceil(wait))
        bucket.reserve(now)
        self._server.reserve(now)
        return None
