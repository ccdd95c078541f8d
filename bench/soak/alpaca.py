"""The Alpaca clients: pollers, a commander that slews, aborts, moves and parks, the final slew."""

from __future__ import annotations

import asyncio
import contextlib
import random
from typing import Any

import aiohttp

from bench.soak.config import COMMAND_BOUND_S, READ_BOUND_S, SLEW_BOUND_S
from bench.soak.night import Night
from bench.soak.targets import random_target, separation_deg


class Alpaca:
    """An Alpaca client on one keep-alive HTTP session."""

    def __init__(self, session: aiohttp.ClientSession, port: int, night: Night) -> None:
        self._session = session
        self._base = f"http://127.0.0.1:{port}/api/v1/telescope/0"
        self._night = night
        self._transaction = 0

    async def _request(self, method: str, member: str, form: dict[str, str]) -> Any:
        self._transaction += 1
        params = {"ClientID": "7", "ClientTransactionID": str(self._transaction)}
        url = f"{self._base}/{member}"
        if method == "GET":
            response = self._session.get(url, params={**params, **form})
        else:
            response = self._session.put(url, data={**params, **form})
        async with response as answer:
            answer.raise_for_status()
            reply: dict[str, Any] = await answer.json()
        if reply.get("ErrorNumber", 0) != 0:
            self._night.answered_error("alpaca", str(reply.get("ErrorMessage")))
            return None
        return reply.get("Value")

    async def get(self, member: str) -> Any:
        work = self._request("GET", member, {})
        try:
            return await self._night.timed("alpaca", f"GET {member}", READ_BOUND_S, work)
        except aiohttp.ClientError as error:
            self._night.broken.append(f"alpaca GET {member} at {self._night.now():.1f} s: {error}")
            return None

    async def put(self, member: str, **form: str) -> bool:
        """True when the device accepted the command (errors are answers too, and counted)."""
        work = self._request("PUT", member, form)
        before = self._night.of("alpaca").errors
        try:
            await self._night.timed("alpaca", f"PUT {member}", COMMAND_BOUND_S, work)
        except aiohttp.ClientError as error:
            self._night.broken.append(f"alpaca PUT {member} at {self._night.now():.1f} s: {error}")
            return False
        return self._night.of("alpaca").errors == before


async def alpaca_poller(alpaca: Alpaca, night: Night, period_s: float) -> None:
    """Reads what an imaging program's mount panel shows, several times a second."""
    while True:
        for member in ("rightascension", "declination", "slewing", "tracking"):
            with contextlib.suppress(TimeoutError):
                await alpaca.get(member)
        await asyncio.sleep(period_s)


async def wait_until_still(alpaca: Alpaca, night: Night, what: str) -> float | None:
    """Seconds until Alpaca says Slewing false, or None (recorded as stuck) past the bound."""
    start = night.now()
    while night.now() - start < SLEW_BOUND_S:
        with contextlib.suppress(TimeoutError):
            if await alpaca.get("slewing") is False:
                return night.now() - start
        await asyncio.sleep(0.1)
    night.stuck.append(f"{what} at {start:.1f} s: still slewing after {SLEW_BOUND_S:g} s")
    return None


async def alpaca_commander(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    """Slews, aborts, tracking on and off, MoveAxis, park and unpark, in a random order."""
    await alpaca.put("connected", Connected="True")
    await alpaca.put("tracking", Tracking="True")
    while True:
        action = chance.choices(
            ["slew", "abort", "tracking", "move", "park"], weights=[5, 2, 2, 2, 1]
        )[0]
        with contextlib.suppress(TimeoutError):
            await _alpaca_action(action, alpaca, night, chance)
        await asyncio.sleep(chance.uniform(0.3, 1.5))


async def _alpaca_action(action: str, alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    match action:
        case "slew" | "abort":
            target = random_target(chance)
            night.moved("Alpaca slew")
            accepted = await alpaca.put(
                "slewtocoordinatesasync",
                RightAscension=f"{target.ra_of_date_hours:.6f}",
                Declination=f"{target.dec_of_date_deg:.5f}",
            )
            if action == "abort":
                await asyncio.sleep(chance.uniform(0.0, 0.3))
                night.moved("Alpaca abort")
                await alpaca.put("abortslew")
            if accepted:
                night.slews += 1
                took = await wait_until_still(alpaca, night, f"Alpaca {action}")
                if took is not None:
                    night.slew_times.append(took)
        case "tracking":
            await alpaca.put("tracking", Tracking="False")
            await asyncio.sleep(chance.uniform(0.5, 2.0))  # the x100 sky turns 0.4 deg/s meanwhile
            await alpaca.put("tracking", Tracking="True")
        case "move":
            # 0.05 deg/s in the emulator's x100 time: 5 deg/s real for a fraction of a second
            rate = chance.choice(["0.05", "-0.05"])
            night.moved("Alpaca MoveAxis")
            if await alpaca.put("moveaxis", Axis=str(chance.randrange(2)), Rate=rate):
                await asyncio.sleep(chance.uniform(0.1, 0.5))
                night.moved("Alpaca MoveAxis stop")
                await alpaca.put("moveaxis", Axis="0", Rate="0")
                await alpaca.put("moveaxis", Axis="1", Rate="0")
                await wait_until_still(alpaca, night, "Alpaca MoveAxis stop")
        case "park":
            night.moved("Alpaca park")
            if await alpaca.put("park"):
                await wait_until_still(alpaca, night, "Alpaca park")
            await asyncio.sleep(chance.uniform(0.5, 2.0))
            await alpaca.put("unpark")
            await alpaca.put("tracking", Tracking="True")


async def final_slew(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    """One more slew once the faults are over; its outcome goes to ``night.final_landing`` (a
    request without an answer is recorded as late and leaves the landing unknown)."""
    with contextlib.suppress(TimeoutError):
        await _final_slew_steps(alpaca, night, chance)


async def _final_slew_steps(alpaca: Alpaca, night: Night, chance: random.Random) -> None:
    await alpaca.put("unpark")
    await alpaca.put("tracking", Tracking="True")
    target = random_target(chance)
    night.moved("final slew")
    await alpaca.put(
        "slewtocoordinatesasync",
        RightAscension=f"{target.ra_of_date_hours:.6f}",
        Declination=f"{target.dec_of_date_deg:.5f}",
    )
    took = await wait_until_still(alpaca, night, "final slew")
    # The landing reading at once: the x100 sky moves 0.4 deg/s under a mount that stopped tracking
    ra, dec = await alpaca.get("rightascension"), await alpaca.get("declination")
    miss = separation_deg(ra, dec, target.ra_of_date_hours, target.dec_of_date_deg)
    night.final_landing = (took, miss)
