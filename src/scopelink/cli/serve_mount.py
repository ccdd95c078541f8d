"""The mount of a running ``scopelink serve``, driven through its dashboard's JSON API.

:class:`ServeMount` offers what the CLI's commands use of a :class:`~scopelink.mount.Mount`
(state, identity, capabilities, site, gotos, sync, stop, moves, tracking, park, unpark, site
and time) as requests to ``/api/...`` of the serve's dashboard on this machine. Each command
runs in the serve's process, through the serve's own Mount: its horizon, limits, Sun avoidance
and access policy (read-only, pairing) hold for these commands as for any other front end.
Anything else (guide pulses, ``park --at``, the Sky Commander's memory) is refused in one line
as a :class:`~scopelink.mount.NotSupportedError` naming what cannot be done this way.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import time
import urllib.error
import urllib.request
from collections.abc import AsyncIterator, Callable, Mapping
from datetime import UTC, datetime, timedelta
from typing import Any, Final, NoReturn

from scopelink.astro import Site
from scopelink.astro.catalog import CatalogObject, lookup
from scopelink.cli.serve_registry import ServeEntry
from scopelink.mount import (
    AlignmentMode,
    Capabilities,
    Identity,
    MountAxis,
    MountError,
    MountState,
    NotSupportedError,
    PierSide,
    SlewProgress,
    SlewTarget,
    TrackingMode,
)
from scopelink.mount import errors as mount_errors
from scopelink.mount.parking import Resume
from scopelink.mount.progress import ProgressTracker

__all__ = ["DIRECT", "POLL_S", "REQUEST_TIMEOUT_S", "ServeMount"]

REQUEST_TIMEOUT_S: Final = 10.0
"""How long one request to the serve may take (a park or goto returns once started)."""
POLL_S: Final = 0.5
"""How often a slew or ``status --watch`` reads the serve's state."""
_PIER: Final = {"east": PierSide.EAST, "west": PierSide.WEST}


class _NoRedirects(urllib.request.HTTPRedirectHandler):
    """A redirect is an answer, not a hop: the pairing token goes nowhere else."""

    def redirect_request(self, *args: Any, **kwargs: Any) -> None:
        return None


DIRECT: Final = urllib.request.build_opener(urllib.request.ProxyHandler({}), _NoRedirects)
"""Straight to the serve on this machine: no ``http_proxy`` of the environment (it would get
the pairing token and every command, and reach its own 127.0.0.1), no redirect followed."""


class ServeMount:
    """The serve's mount (see the module docstring). Built by :meth:`open`."""

    _live: tuple[Any, asyncio.Task[None], str] | None = None
    """While a motion of this command's may run: the HTTP client, the task reading the live
    connection, and its session."""

    def __init__(self, entry: ServeEntry, described: dict[str, Any]) -> None:
        assert entry.dashboard is not None
        self.entry = entry
        self.url = entry.dashboard.rstrip("/")
        self._token = entry.about.get("pairing")
        identity = described["identity"]
        self.identity = Identity(
            identity["protocol"],
            identity["model"],
            identity.get("firmware") or "",
            f"{identity.get('link') or identity['protocol']} via scopelink serve (PID {entry.pid})",
        )
        caps = described["capabilities"]
        self.capabilities = Capabilities(
            alignment_mode=AlignmentMode(caps["alignment_mode"]),
            can_goto=caps["can_goto"],
            can_goto_altaz=caps["can_goto"],
            can_sync=caps["can_sync"],
            can_park=caps["can_park"],
            can_move_axis=(bool(caps["can_move_axis"][0]), bool(caps["can_move_axis"][1])),
            max_axis_rate_deg_s=caps["max_axis_rate_deg_s"],
            tracking_modes=frozenset(TrackingMode(mode) for mode in caps["tracking_modes"]),
            can_set_site=caps["can_set_site"],
            can_set_time=caps["can_set_time"],
        )
        site = described["site"]
        self.site = Site(site["latitude_deg"], site["longitude_deg"], site["elevation_m"])
        self.state = MountState(read_at=datetime.now(UTC))
        self.target: SlewTarget | None = None

    @classmethod
    async def open(cls, entry: ServeEntry) -> ServeMount:
        """Ask the serve who its mount is; a :class:`MountError` if it cannot be reached."""
        if entry.dashboard is None:
            raise NotSupportedError(
                f"the running scopelink serve (PID {entry.pid}) has no dashboard, through which "
                "the command line drives it: restart it without --dashboard-port -1"
            )
        probe = cls.__new__(cls)
        probe.url, probe._token, probe.entry = entry.dashboard.rstrip("/"), None, entry
        answer = await probe._request("GET", "/api/state")
        mount = cls(entry, answer["mount"])
        mount._take(answer["state"])
        return mount

    # --- what the commands read ---------------------------------------------------------------

    def now(self) -> datetime:
        """The mount's clock, as of its last reading plus the time since."""
        return self.state.read_at + timedelta(seconds=self.state.age_s())

    async def refresh(self) -> MountState:
        return self._take((await self._request("GET", "/api/state"))["state"])

    async def states(self) -> AsyncIterator[MountState]:
        while True:
            yield await self.refresh()
            await asyncio.sleep(POLL_S)

    async def wait_for_slew(
        self,
        timeout_s: float | None = None,
        progress: Callable[[SlewProgress], None] | None = None,
    ) -> MountState:
        """Read the serve's state until the slew has ended (a reading after this call began)."""
        since = time.monotonic()
        tracker = ProgressTracker(self.target)
        async with asyncio.timeout(timeout_s):
            while True:
                state = await self.refresh()
                if progress is not None:
                    progress(tracker.update(state))
                if state.connected and not state.slewing and state.received_s > since:
                    return state
                await asyncio.sleep(POLL_S)

    # --- commands -----------------------------------------------------------------------------

    async def goto_object(self, name: str) -> CatalogObject:
        # The same offline catalogue as the serve's: an unknown name is told here, with the
        # closest names; the serve looks the name up again at its own time.
        found = lookup(name, self.now(), self.site)
        await self._command("/api/goto", {"name": name})
        return found

    async def goto_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        await self._command("/api/goto", {"ra_hours": ra_j2000_hours, "dec_deg": dec_j2000_deg})

    async def goto_horizontal(self, alt_deg: float, az_deg: float) -> None:
        await self._command("/api/goto", {"alt_deg": alt_deg, "az_deg": az_deg})

    async def sync_equatorial(self, ra_j2000_hours: float, dec_j2000_deg: float) -> None:
        await self._command("/api/sync", {"ra_hours": ra_j2000_hours, "dec_deg": dec_j2000_deg})

    async def abort(self) -> None:
        await self._command("/api/abort", {})

    async def move_axis(self, axis: MountAxis, rate_deg_s: float) -> None:
        body: dict[str, object] = {"axis": axis.name.lower(), "rate_deg_s": rate_deg_s}
        if rate_deg_s != 0.0:
            body["session"] = await self._live_session()
        await self._command("/api/move", body)

    async def _live_session(self) -> str:
        """The session of a live connection to the serve, held until :meth:`disconnect`: the
        serve's dead-man stops this command's motions when the connection goes (the process
        killed outright, the machine asleep), as it does a dashboard page's."""
        if self._live is not None:
            return self._live[2]
        import aiohttp  # noqa: PLC0415 - only for a rate motion

        http = aiohttp.ClientSession(trust_env=False)  # no proxy: straight to the serve
        try:
            async with asyncio.timeout(REQUEST_TIMEOUT_S):
                socket = await http.ws_connect(self.url + "/ws", max_msg_size=0)
                hello = await socket.receive_json()
            token = hello["session"]
            if not isinstance(token, str):
                raise TypeError("no session")
        except (aiohttp.ClientError, TimeoutError, ValueError, TypeError, KeyError) as error:
            await http.close()
            raise MountError(
                f"the running scopelink serve (PID {self.entry.pid}) gives no live connection "
                f"at {self.url}/ws, which a motion needs (its dead-man): {error or type(error)}"
            ) from None
        reading = asyncio.create_task(_read_until_closed(socket), name="serve live connection")
        self._live = (http, reading, token)
        return token

    async def set_tracking(self, mode: TrackingMode) -> None:
        await self._command("/api/tracking", {"mode": mode.value})

    async def park(self) -> None:
        await self._command("/api/park", {})

    async def unpark(self) -> Resume:
        answer = await self._command("/api/unpark", {})
        return Resume(str(answer.get("resume") or "allowed to move again"))

    async def set_site(self, site: Site) -> None:
        body = {
            "latitude_deg": site.latitude_deg,
            "longitude_deg": site.longitude_deg,
            "elevation_m": site.elevation_m,
        }
        await self._command("/api/site", body)
        self.site = site

    async def set_time(self, utc: datetime) -> None:
        await self._command("/api/time", {"utc": utc.isoformat()})

    async def disconnect(self) -> None:
        """The live connection closed (the serve keeps its mount)."""
        live, self._live = self._live, None
        if live is not None:
            http, reading, _ = live
            reading.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reading
            await http.close()

    @property
    def park_position(self) -> NoReturn:
        raise self.cannot("reading the park position")

    @park_position.setter
    def park_position(self, position: object) -> None:
        raise self.cannot(
            "parking elsewhere (--at, --axes)", "the serve parks where its [park] setting says"
        )

    def __getattr__(self, name: str) -> NoReturn:
        if name.startswith("__"):  # Python's own protocols: not a mount feature
            raise AttributeError(name)
        raise self.cannot(name.strip("_").replace("_", " "))

    # --- the wire ---------------------------------------------------------------------------------

    def cannot(self, what: str, hint: str = "") -> NotSupportedError:
        """The one-line refusal of what the serve's API does not offer."""
        return NotSupportedError(
            f"{what}: cannot be done through a running scopelink serve (PID {self.entry.pid})"
            + (f"; {hint}" if hint else "; stop the serve and give --device DEVICE")
        )

    def _take(self, state: dict[str, Any]) -> MountState:
        self.state = _state(state)
        target = state.get("target")
        self.target = (
            SlewTarget(
                target.get("ra_j2000_hours"),
                target.get("dec_j2000_deg"),
                target.get("alt_deg"),
                target.get("az_deg"),
                target.get("name") or "",
            )
            if isinstance(target, dict)
            else None
        )
        return self.state

    async def _command(self, path: str, body: Mapping[str, object]) -> dict[str, Any]:
        answer = await self._request("POST", path, body)
        if isinstance(answer.get("state"), dict):
            self._take(answer["state"])
        return answer

    async def _request(
        self, method: str, path: str, body: Mapping[str, object] | None = None
    ) -> dict[str, Any]:
        return await asyncio.to_thread(self._request_now, method, path, body)

    def _request_now(
        self, method: str, path: str, body: Mapping[str, object] | None
    ) -> dict[str, Any]:
        headers = {"Content-Type": "application/json"}
        if isinstance(self._token, str):
            from scopelink.web.dashboard import PAIRING_HEADER  # noqa: PLC0415 - if paired

            headers[PAIRING_HEADER] = self._token
        data = None if body is None else json.dumps(dict(body)).encode()
        request = urllib.request.Request(self.url + path, data, headers, method=method)
        try:
            with DIRECT.open(request, timeout=REQUEST_TIMEOUT_S) as response:
                answer = json.loads(response.read())
        except urllib.error.HTTPError as error:
            raise _refusal(error) from None
        except (urllib.error.URLError, OSError, ValueError) as error:
            reason = getattr(error, "reason", error)
            raise MountError(
                f"the running scopelink serve (PID {self.entry.pid}) does not answer at "
                f"{self.url}: {reason}"
            ) from None
        if not isinstance(answer, dict):
            raise MountError(f"{self.url} did not answer as a scopelink dashboard")
        return answer


async def _read_until_closed(socket: Any) -> None:
    """Read (and drop) the serve's updates, so that its pings are answered."""
    async for _ in socket:
        pass


def _refusal(error: urllib.error.HTTPError) -> Exception:
    """The serve's JSON error as the exception its Mount raised (so the CLI's hints apply)."""
    try:
        body = json.loads(error.read())
    except (ValueError, OSError):
        body = {}
    message = str(body.get("error") or f"the serve answered {error.code} {error.reason}")
    kind = getattr(mount_errors, str(body.get("kind")), None)
    if isinstance(kind, type) and issubclass(kind, MountError):
        return kind(message)
    return MountError(f"the serve refused: {message}")


def _state(data: dict[str, Any]) -> MountState:
    now = time.monotonic()
    return MountState(
        read_at=datetime.fromisoformat(data["read_at"]),
        connected=bool(data["connected"]),
        ra_j2000_hours=data.get("ra_j2000_hours"),
        dec_j2000_deg=data.get("dec_j2000_deg"),
        ra_of_date_hours=data.get("ra_of_date_hours"),
        dec_of_date_deg=data.get("dec_of_date_deg"),
        alt_deg=data.get("alt_deg"),
        az_deg=data.get("az_deg"),
        pier_side=_PIER.get(str(data.get("pier_side")), PierSide.UNKNOWN),
        slewing=bool(data["slewing"]),
        tracking=TrackingMode(data["tracking"]),
        parked=bool(data["parked"]),
        aligned=bool(data.get("aligned")),
        pulse_guiding=bool(data.get("pulse_guiding")),
        problems=tuple(str(problem) for problem in data.get("problems") or ()),
        received_s=now - float(data.get("state_age_s") or 0.0),
        position_received_s=now - float(data.get("age_s") or 0.0),
    )
