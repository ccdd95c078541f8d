"""Who may talk to the servers, how many at once, how fast, and whether they may change anything.

One :class:`AccessPolicy` (what ``scopelink serve --read-only --allow CIDR ...`` says) is shared
by every server; each server builds its own :class:`AccessControl` from it, so a flood on one
protocol's port does not lock clients out of another. What it decides, protocol-neutrally:

- **allow-list**: an empty list lets every address in (the bind address is the first fence); a
  non-empty one admits only those networks, plus loopback unless ``loopback_always_allowed`` is
  off (tests turn it off to see a refusal without another machine).
- **connection limits**: in total per server, and per client address.
- **rate**: a token bucket per client address (``requests_per_s``, ``burst``) and one for the
  whole server (``server_requests_per_s``, ``server_burst``), which bounds what any number of
  clients can make the server do, so that the mount's poller keeps its share. How excess is
  handled is the server's choice, because each protocol has its own: line protocols (LX200,
  SynScan, Stellarium) wait (:meth:`Client.throttle`), which reads to the client as a slower
  line and loses nothing; HTTP waits up to ``max_delay_s`` and answers 429 beyond it.
- **read-only**: :attr:`AccessPolicy.read_only`; each server refuses state-changing commands with
  its protocol's own refusal (``docs/reliability-security.md`` lists them).

Connections that do not come from a TCP peer (a pty, a memory pair) count as local: admitted,
not counted, not throttled.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import logging
import math
import time
from collections.abc import AsyncIterator, Callable
from contextvars import ContextVar
from dataclasses import dataclass, field

from scopelink.mount import MountError
from scopelink.servers.buckets import KeyedBuckets, TokenBucket

__all__ = [
    "DEFAULT_POLICY",
    "OPEN_POLICY",
    "AccessControl",
    "AccessPolicy",
    "Client",
    "IPNetwork",
    "ReadOnlyError",
    "Refusal",
    "TokenBucket",
    "current_client",
    "parse_network",
    "retry_after",
]

logger = logging.getLogger(__name__)

IPNetwork = ipaddress.IPv4Network | ipaddress.IPv6Network


class ReadOnlyError(MountError):
    """A state-changing command reached a read-only server."""

    def __init__(self, what: str = "this command") -> None:
        super().__init__(f"{what} refused: the server is read-only")


def retry_after(wait_s: float) -> str:
    """An HTTP ``Retry-After`` value for a wait: whole seconds, at least one."""
    return str(max(1, math.ceil(wait_s)))


def parse_network(text: str) -> IPNetwork:
    """``192.168.1.0/24``, ``10.0.0.7`` (one host) or ``fd00::/8``; ValueError names the text."""
    try:
        return ipaddress.ip_network(text.strip(), strict=False)
    except ValueError:
        raise ValueError(
            f"{text!r} is not an IP network (expected e.g. 192.168.1.0/24 or 10.0.0.7)"
        ) from None


@dataclass(frozen=True, slots=True)
class AccessPolicy:
    """What every server admits and allows; the defaults are those of ``scopelink serve``."""

    read_only: bool = False
    allow: tuple[IPNetwork, ...] = ()
    """Networks admitted; empty admits every address."""
    loopback_always_allowed: bool = True
    max_connections: int = 64
    """Connections at once per server (NINA uses 1-4, SkySafari 1, Stellarium 1)."""
    max_connections_per_client: int = 16
    requests_per_s: float = 250.0
    """Sustained commands or requests per second per client address: a client polling 20
    properties at 10 Hz (NINA with a busy sequence: 200/s) is never delayed; SkySafari and
    Stellarium send a few."""
    burst: int = 500
    server_requests_per_s: float = 500.0
    """Sustained commands or requests per second per server, from all clients together: what
    keeps a crowd of clients from taking the event loop from the mount's poller
    (``bench/security_flood.py`` measures what the poller keeps under a flood)."""
    server_burst: int = 500
    max_delay_s: float = 0.25
    """HTTP: the longest a request is held for its token before the answer is 429 with
    ``Retry-After``: a short hold absorbs jitter, beyond it the client is told, not queued."""
    idle_timeout_s: float = 180.0
    """A connection that sends nothing for this long is closed (every TCP server but
    Stellarium, whose clients speak only to command a goto): three polls of a planetarium that
    polls once a minute."""
    header_timeout_s: float = 10.0
    """HTTP: from the first byte of a request head to its end; a slower head is cut off."""

    def __post_init__(self) -> None:
        if self.max_connections < 1 or self.max_connections_per_client < 1:
            raise ValueError("connection limits must be at least 1")
        if not (self.requests_per_s > 0.0 and self.server_requests_per_s > 0.0):
            raise ValueError("the request rates must be positive")
        if self.burst < 1 or self.server_burst < 1:
            raise ValueError("the bursts must be at least 1")
        if self.max_delay_s < 0.0:
            raise ValueError("the maximum delay cannot be negative")
        if not (self.idle_timeout_s > 0.0 and self.header_timeout_s > 0.0):
            raise ValueError("the timeouts must be positive")

    def allows(self, host: str) -> bool:
        """Whether a client at ``host`` (an IP address text) may connect at all."""
        try:
            address = ipaddress.ip_address(host.split("%", 1)[0])
        except ValueError:
            return False
        if isinstance(address, ipaddress.IPv6Address) and address.ipv4_mapped is not None:
            address = address.ipv4_mapped
        if self.loopback_always_allowed and address.is_loopback:
            return True
        if not self.allow:
            return True
        return any(address in network for network in self.allow)

    def describe(self) -> str:
        """One line for ``scopelink serve``'s "what listens where"."""
        who = "any address"
        if self.allow:
            networks = ", ".join(str(network) for network in self.allow)
            loopback = " + loopback" if self.loopback_always_allowed else ""
            who = f"{networks}{loopback}"
        mode = "read-only" if self.read_only else "read-write"
        return (
            f"{mode}; clients: {who}; at most {self.max_connections} connections per server, "
            f"{self.max_connections_per_client} per client; "
            f"{self.requests_per_s:g} requests/s per client, "
            f"{self.server_requests_per_s:g} per server"
        )


DEFAULT_POLICY = AccessPolicy()
OPEN_POLICY = AccessPolicy(
    max_connections=1_000_000,
    max_connections_per_client=1_000_000,
    requests_per_s=1e12,
    burst=1_000_000_000,
    server_requests_per_s=1e12,
    server_burst=1_000_000_000,
)
"""No limit at all: what a server built without a policy uses (library use, benchmarks)."""


@dataclass(frozen=True, slots=True)
class Refusal:
    """Why a connection was not admitted: ``forbidden`` (allow-list) or ``busy`` (a limit)."""

    reason: str
    forbidden: bool
    total: bool = False
    """Refused by the server's total connection limit (not the address's own)."""


@dataclass(eq=False, slots=True)
class Client:
    """One admitted connection; its address's bucket is shared by all that address's
    connections to the same server."""

    host: str
    control: AccessControl | None
    bucket: TokenBucket | None
    released: bool = field(default=False)

    async def throttle(self) -> None:
        """Wait for this client's next token (line protocols: the excess waits, nothing drops)."""
        if self.control is None:
            return
        wait = self.control.take(self.bucket)
        if wait:
            await asyncio.sleep(wait)

    def admit_request(self) -> float | None:
        """HTTP: the wait before handling this request, or None to answer 429 now."""
        if self.control is None:
            return 0.0
        return self.control.take(self.bucket, max_wait_s=self.control.policy.max_delay_s)

    def retry_after_s(self) -> float:
        return 0.0 if self.control is None else self.control.wait_for_one(self.bucket)

    def release(self) -> None:
        if not self.released:
            self.released = True
            if self.control is not None:
                self.control.release(self)


LOCAL_CLIENT_HOST = "local"


class AccessControl:
    """One server's enforcement of a policy: admission, counters, buckets."""

    def __init__(
        self,
        policy: AccessPolicy | None = None,
        name: str = "server",
        *,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.policy = policy if policy is not None else OPEN_POLICY
        self.name = name
        self.clock = clock
        self._per_host: dict[str, int] = {}
        # Four buckets per connection allowed (+1: the one being made) before idle ones go.
        self._buckets = KeyedBuckets(
            self.policy.requests_per_s, self.policy.burst, 4 * self.policy.max_connections + 1
        )
        self._server_bucket = TokenBucket(
            self.policy.server_requests_per_s, self.policy.server_burst, clock()
        )
        self.open_connections = 0
        self.forbidden = 0
        """Connections and datagrams refused by the allow-list."""
        self.refused_connections = 0
        """Connections refused by a connection limit."""
        self.refused_requests = 0
        """HTTP requests answered 429."""
        self.delayed = 0
        """Requests or commands that waited for their token."""

    @property
    def read_only(self) -> bool:
        return self.policy.read_only

    def allows(self, host: str | None) -> bool:
        """Whether ``host`` may talk to us at all (datagrams: ignore when False)."""
        if host is None:
            return True
        if self.policy.allows(host):
            return True
        self.forbidden += 1
        return False

    def admit(self, host: str | None) -> Client | Refusal:
        """A new connection from ``host`` (None: not a network peer, always admitted)."""
        if host is None:
            return Client(LOCAL_CLIENT_HOST, self, None)
        if not self.allows(host):
            logger.warning("%s: connection from %s refused (allow-list)", self.name, host)
            return Refusal(f"{host} is not in this server's allow-list", forbidden=True)
        policy = self.policy
        # The address's own cap first: an address at its cap must not evict others (HTTP).
        if self._per_host.get(host, 0) >= policy.max_connections_per_client:
            self.refused_connections += 1
            limit = policy.max_connections_per_client
            logger.info("%s: %s refused: %d open from there", self.name, host, limit)
            return Refusal(f"{host} already has {limit} connections to {self.name}", False)
        if self.open_connections >= policy.max_connections:
            self.refused_connections += 1
            limit = policy.max_connections
            logger.info("%s: connection from %s refused: %d open", self.name, host, limit)
            reason = f"{self.name} has {policy.max_connections} connections open"
            return Refusal(reason, forbidden=False, total=True)
        self.open_connections += 1
        self._per_host[host] = self._per_host.get(host, 0) + 1
        return Client(host, self, self._bucket_of(host))

    def take(self, bucket: TokenBucket | None, max_wait_s: float = math.inf) -> float | None:
        """One token from ``bucket`` (a client's) and from the server's: the wait until both are
        there, or None (nothing taken) when that would exceed ``max_wait_s``."""
        if bucket is None:
            return 0.0  # not a network client
        now = self.clock()
        needed = max(bucket.wait_for_one(now), self._server_bucket.wait_for_one(now))
        if needed > max_wait_s:
            self.refused_requests += 1
            return None
        wait = max(bucket.reserve(now) or 0.0, self._server_bucket.reserve(now) or 0.0)
        if wait:
            self.delayed += 1
        return wait

    def wait_for_one(self, bucket: TokenBucket | None) -> float:
        """How long until a request from ``bucket``'s client would go through (Retry-After)."""
        if bucket is None:
            return 0.0
        now = self.clock()
        return max(bucket.wait_for_one(now), self._server_bucket.wait_for_one(now))

    def request_wait(self, host: str | None) -> float | None:
        """For servers without connection hooks (the dashboard): take a token for one request
        from ``host``; the wait before handling it, or None to refuse it (429)."""
        if host is None:
            return 0.0
        return self.take(self._bucket_of(host), max_wait_s=self.policy.max_delay_s)

    def retry_after_s(self, host: str) -> float:
        return self.wait_for_one(self._buckets.get(host))

    def _bucket_of(self, host: str) -> TokenBucket:
        return self._buckets.of(host, self.clock(), busy=self._per_host)

    def release(self, client: Client) -> None:
        """``client``'s connection has ended (:meth:`Client.release` calls this once)."""
        if client.bucket is None:
            return
        self.open_connections -= 1
        left = self._per_host.get(client.host, 1) - 1
        if left > 0:
            self._per_host[client.host] = left
            return
        self._per_host.pop(client.host, None)
        # Forget an idle address's bucket only when full: reconnecting must not refill it.
        self._buckets.forget_if_full(client.host, self.clock())
        self._buckets.prune(self.clock(), busy=self._per_host)

    @contextlib.asynccontextmanager
    async def session(self, host: str | None) -> AsyncIterator[Client | Refusal]:
        """Admit ``host`` for the body (the refusal is yielded instead when it is refused) and
        make the client :func:`current_client` inside it."""
        admitted = self.admit(host)
        if isinstance(admitted, Refusal):
            yield admitted
            return
        token = _CURRENT.set(admitted)
        try:
            yield admitted
        finally:
            _CURRENT.reset(token)
            admitted.release()


_UNLIMITED = Client(LOCAL_CLIENT_HOST, None, None)
_CURRENT: ContextVar[Client] = ContextVar("scopelink_access_client", default=_UNLIMITED)


def current_client() -> Client:
    """The client whose connection the running task serves (an unlimited one outside any)."""
    return _CURRENT.get()
