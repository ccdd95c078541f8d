"""The LX200 server over real TCP sockets (and UDP for SkyFi) in front of the simulated mount."""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from datetime import UTC, datetime

import pytest

from scopelink.astro import (
    Site,
    angular_separation_deg,
    apparent_to_j2000,
    j2000_to_apparent,
    observed_to_j2000,
)
from scopelink.mount import TrackingMode
from scopelink.protocol.lx200 import DATE_SET_REPLY, parse_sexagesimal
from scopelink.servers.lx200 import LX200Config, LX200Server, SyncReply
from scopelink.servers.lx200 import server as server_module
from scopelink.sim import AZ_GTI, EQ6, MountModel, SimClock, SimulatedMount

SITE = Site(48.2, 16.4)
START = datetime(2026, 3, 1, 22, 0, tzinfo=UTC)
TOLERANCE_DEG = 0.01


def simulated_mount(rate: float = 30.0, model: MountModel = EQ6) -> SimulatedMount:
    return SimulatedMount(model, site=SITE, clock=SimClock(start=START, rate=rate))


class Client:
    """A raw LX200 client: writes commands, reads replies by their documented shapes."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.reader = reader
        self.writer = writer

    async def send(self, data: bytes) -> None:
        self.writer.write(data)
        await self.writer.drain()

    async def char(self, command: bytes) -> bytes:
        await self.send(command)
        async with asyncio.timeout(5):
            return await self.reader.readexactly(1)

    async def text(self, command: bytes) -> bytes:
        await self.send(command)
        async with asyncio.timeout(5):
            return await self.reader.readuntil(b"#")

    async def slew(self, command: bytes = b":MS#") -> bytes:
        first = await self.char(command)
        if first == b"0":
            return first
        async with asyncio.timeout(5):
            return first + await self.reader.readuntil(b"#")

    async def nothing_more(self, seconds: float = 0.3) -> bool:
        try:
            async with asyncio.timeout(seconds):
                await self.reader.read(1)
        except TimeoutError:
            return True
        return False

    async def jnow(self) -> tuple[float, float]:
        ra = parse_sexagesimal((await self.text(b":GR#"))[:-1].decode("latin-1"))
        dec = parse_sexagesimal((await self.text(b":GD#"))[:-1].decode("latin-1"))
        assert ra is not None
        assert dec is not None
        return ra, dec

    async def set_target(self, ra_hours: float, dec_deg: float, degree: bytes = b"*") -> None:
        ra = f"{int(ra_hours):02d}:{int(ra_hours * 60) % 60:02d}:{int(ra_hours * 3600) % 60:02d}"
        sign = "-" if dec_deg < 0 else "+"
        d = abs(dec_deg)
        dec = f"{sign}{int(d):02d}{degree.decode('latin-1')}"
        dec += f"{int(d * 60) % 60:02d}:{int(d * 3600) % 60:02d}"
        assert await self.char(f":Sr {ra}#".encode()) == b"1"
        assert await self.char(f":Sd {dec}#".encode("latin-1")) == b"1"


@asynccontextmanager
async def serving(
    mount: SimulatedMount, config: LX200Config | None = None
) -> AsyncIterator[tuple[LX200Server, Client]]:
    async with LX200Server(mount, config) as server:
        host, port = await server.on_tcp(port=0)
        reader, writer = await asyncio.open_connection(host, port)
        try:
            yield server, Client(reader, writer)
        finally:
            writer.close()
            await writer.wait_closed()


def separation(a: tuple[float, float], b: tuple[float, float]) -> float:
    return angular_separation_deg(a[0] * 15.0, a[1], b[0] * 15.0, b[1])


def jnow_of(mount: SimulatedMount) -> tuple[float, float]:
    state = mount.snapshot()
    assert state.ra_of_date_hours is not None
    assert state.dec_of_date_deg is not None
    return state.ra_of_date_hours, state.dec_of_date_deg


def jnow_up_in_the_south(mount: SimulatedMount, alt_deg: float) -> tuple[float, float]:
    return j2000_to_apparent(*observed_to_j2000(alt_deg, 180.0, mount.now(), mount.site), START)


async def test_ack_and_stacked_reads_give_the_mounts_jnow_position() -> None:
    mount = simulated_mount(rate=1.0)
    async with serving(mount) as (_, client):
        assert await client.char(b"\x06") == b"G"
        await client.send(b"#:GR#:GD#")
        ra_text = await client.reader.readuntil(b"#")
        dec_text = await client.reader.readuntil(b"#")
        assert len(ra_text) == 9  # HH:MM:SS#
        assert len(dec_text) == 10  # sDD*MM:SS#
        ra = parse_sexagesimal(ra_text[:-1].decode("latin-1"))
        dec = parse_sexagesimal(dec_text[:-1].decode("latin-1"))
        assert ra is not None
        assert dec is not None
        assert separation((ra, dec), jnow_of(mount)) < TOLERANCE_DEG
        alt = await client.text(b":GA#")
        az = await client.text(b":GZ#")
        assert alt.startswith(b"+")
        assert b"'" in alt
        assert len(az) == 10


async def test_alt_az_mounts_answer_a() -> None:
    async with serving(simulated_mount(model=AZ_GTI)) as (_, client):
        assert await client.char(b"\x06") == b"A"
        assert (await client.text(b":GW#"))[:1] == b"A"


async def test_precision_toggles_per_connection() -> None:
    async with serving(simulated_mount()) as (_, client):
        await client.send(b":U#")
        assert len(await client.text(b":GR#")) == 8  # HH:MM.T#
        assert len(await client.text(b":GD#")) == 7  # sDD*MM#
        await client.send(b":U#")
        assert len(await client.text(b":GR#")) == 9


async def test_goto_slews_to_the_jnow_target_with_distance_bars() -> None:
    mount = simulated_mount()
    async with serving(mount) as (_, client):
        target = jnow_up_in_the_south(mount, 55.0)
        await client.set_target(*target)
        assert await client.slew() == b"0"
        assert await client.text(b":D#") == b"\x7f#"
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        await asyncio.sleep(0.2)
        assert await client.text(b":D#") == b"#"
        assert separation(await client.jnow(), target) < TOLERANCE_DEG
        assert mount.target is not None
        assert mount.target.ra_j2000_hours is not None
        assert mount.target.dec_j2000_deg is not None
        j2000 = apparent_to_j2000(*target, mount.now())
        sent = (mount.target.ra_j2000_hours, mount.target.dec_j2000_deg)
        assert separation(sent, j2000) < TOLERANCE_DEG


async def test_a_goto_below_the_horizon_is_refused_and_the_mount_stays() -> None:
    mount = simulated_mount()
    async with serving(mount) as (_, client):
        before = mount.snapshot()
        below = j2000_to_apparent(*observed_to_j2000(-15.0, 10.0, mount.now(), SITE), START)
        await client.set_target(*below)
        assert await client.slew() == b"1Object below horizon#"
        await asyncio.sleep(0.3)
        after = mount.snapshot()
        assert not after.slewing
        assert mount.target is None
        assert after.alt_deg == pytest.approx(before.alt_deg, abs=0.1)
        assert after.az_deg == pytest.approx(before.az_deg, abs=0.5)
        # Without a target there is nothing to go to.
    async with serving(simulated_mount()) as (_, fresh):
        reply = await fresh.slew()
        assert reply.startswith(b"2No target")


async def test_parked_mount_refuses_with_2() -> None:
    mount = simulated_mount()
    async with serving(mount) as (_, client):
        await mount.park()
        await client.set_target(*jnow_up_in_the_south(mount, 50.0))
        reply = await client.slew()
        assert reply.startswith(b"2")
        assert b"parked" in reply


@pytest.mark.parametrize(
    ("style", "reply"),
    [(SyncReply.STATUS, b"0#"), (SyncReply.MEADE, b"Coordinates     matched.        #")],
)
async def test_sync_in_both_reply_styles(style: SyncReply, reply: bytes) -> None:
    mount = simulated_mount(rate=1.0)
    await mount.connect()  # away from the pole first: a sync there turns the RA axis far
    await mount.goto_horizontal(40.0, 200.0)
    mount.clock.advance(120.0)
    async with serving(mount, LX200Config(sync_reply=style)) as (_, client):
        here = jnow_of(mount)
        synced = (here[0], here[1] - 1.0)
        await client.set_target(*synced)
        assert await client.text(b":CM#") == reply
        assert separation(jnow_of(mount), synced) < TOLERANCE_DEG
        assert await client.nothing_more()


async def test_motion_at_the_selected_rate_and_halts() -> None:
    mount = simulated_mount(rate=30.0)
    async with serving(mount) as (_, client):
        await client.set_target(*jnow_up_in_the_south(mount, 45.0))
        assert await client.slew() == b"0"
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        mount.clock.set_rate(1.0)
        dec_before = jnow_of(mount)[1]
        await client.send(b":RS#:Mn#")
        await asyncio.sleep(0.5)
        await client.send(b":Qn#")
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5)  # the axis ramps down
        dec_after = jnow_of(mount)[1]
        assert dec_after > dec_before + 0.5
        await asyncio.sleep(0.3)
        assert jnow_of(mount)[1] == pytest.approx(dec_after, abs=0.01)
        # west at the guide rate moves RA down by a little; :Q# stops it
        ra_before = jnow_of(mount)[0]
        await client.send(b":RC#:Mw#")
        await asyncio.sleep(1.0)
        await client.send(b":Q#")
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5)
        moved_hours = (ra_before - jnow_of(mount)[0]) % 24.0
        assert 0.0 < moved_hours < 0.1
        assert not mount.snapshot().slewing


async def test_abort_stops_a_goto() -> None:
    mount = simulated_mount(rate=1.0)
    async with serving(mount) as (_, client):
        target = jnow_up_in_the_south(mount, 30.0)
        await client.set_target(*target)
        assert await client.slew() == b"0"
        await asyncio.sleep(0.3)
        await client.send(b":Q#")
        await mount.wait_for(lambda s: not s.slewing, timeout_s=5)  # the axes ramp down
        await asyncio.sleep(0.3)
        assert not mount.snapshot().slewing
        assert separation(jnow_of(mount), target) > 5.0


async def test_pulse_guide() -> None:
    mount = simulated_mount(rate=1.0)
    async with serving(mount) as (_, client):
        started = time.monotonic()
        await client.send(b":Mgn2000#")
        await asyncio.sleep(0.1)
        assert mount.snapshot().pulse_guiding
        await mount.wait_for(lambda s: not s.pulse_guiding, timeout_s=5.0)
        assert time.monotonic() - started >= 1.9  # the pulse's 2 s, not cut short


async def test_site_time_and_date() -> None:
    mount = simulated_mount(rate=1.0)
    async with serving(mount) as (_, client):
        assert await client.char(b":St+10*30#") == b"1"
        assert await client.char(b":Sg350:00#") == b"1"
        assert mount.site.latitude_deg == pytest.approx(10.5)
        assert mount.site.longitude_deg == pytest.approx(10.0)
        assert await client.text(b":Gt#") == b"+10*30#"
        assert await client.text(b":Gg#") == b"-010*00#"
        assert await client.char(b":SG -02#") == b"1"  # UTC+2: add -2 h to local for UTC
        assert await client.char(b":SL 12:00:00#") == b"1"
        await client.send(b":SC 05/04/26#")
        async with asyncio.timeout(5):
            assert (
                await client.reader.readuntil(b"#") + await client.reader.readuntil(b"#")
                == DATE_SET_REPLY
            )
        now = mount.now()
        assert abs((now - datetime(2026, 5, 4, 10, 0, tzinfo=UTC)).total_seconds()) < 30
        assert await client.text(b":GG#") == b"-02.0#"
        assert (await client.text(b":GL#")).startswith(b"12:00:")
        assert await client.text(b":GC#") == b"05/04/26#"
        assert await client.text(b":Gc#") == b"24#"
        assert len(await client.text(b":GS#")) == 9


async def test_identity_and_status() -> None:
    mount = simulated_mount()
    config = LX200Config(product="Test Scope", firmware="9.9")
    async with serving(mount, config) as (_, client):
        assert await client.text(b":GVP#") == b"Test Scope#"
        assert await client.text(b":GVN#") == b"9.9#"
        assert await client.text(b":GVF#") == b"Test Scope 9.9#"
        assert len(await client.text(b":GVD#")) == 12
        assert await client.text(b":GVT#") == b"00:00:00#"
        assert await client.text(b":GM#") == b"scopelink#"
        assert await client.text(b":GW#") == b"GN1#"
        assert await client.text(b":GT#") == b"00.0#"
        await mount.set_tracking(TrackingMode.SIDEREAL)
        await asyncio.sleep(0.2)
        assert await client.text(b":GW#") == b"GT1#"
        assert await client.text(b":GT#") == b"60.1#"


async def test_bad_input_gets_zero_or_silence_and_loses_nothing(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(server_module, "PARTIAL_COMMAND_TIMEOUT_S", 0.2)
    mount = simulated_mount()
    async with serving(mount) as (_, client):
        with caplog.at_level(logging.INFO, logger="scopelink.servers.lx200"):
            assert await client.char(b":Sr 25:00:00#") == b"0"
            assert await client.char(b":Sd +91*00:00#") == b"0"
            assert await client.char(b":SC 02/30/26#") == b"0"
            await client.send(b"garbage\r\n:XY#")
            assert await client.nothing_more()
            await client.send(b":GR")  # a client that gave up half-way
            await asyncio.sleep(0.5)
            assert len(await client.text(b":GD#")) == 10
        assert "unknown command :XY#" in caplog.text
        assert "stray byte" in caplog.text
        assert "incomplete command b':GR' dropped" in caplog.text


async def test_each_connection_has_its_own_target() -> None:
    mount = simulated_mount()
    async with serving(mount) as (server, first):
        host, port = server.address.rsplit(":", 1)
        reader, writer = await asyncio.open_connection(host, int(port))
        second = Client(reader, writer)
        try:
            target = jnow_up_in_the_south(mount, 50.0)
            await first.set_target(*target)
            await second.set_target(*jnow_up_in_the_south(mount, -30.0))
            assert await first.slew() == b"0"
            assert (await second.slew()).startswith(b"1")
        finally:
            writer.close()
            await writer.wait_closed()


async def test_skyfi_auto_detect_answers_on_127_0_0_1() -> None:
    mount = simulated_mount()
    async with LX200Server(mount) as server:
        responder = await server.on_skyfi(port=0, name="Backyard")
        loop = asyncio.get_running_loop()
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as udp:
            udp.setblocking(False)
            udp.bind(("127.0.0.1", 0))
            for query, expected in [
                (b"skyfi?", b"skyfi@127.0.0.1"),
                (b"skyfi:backyard?", b"skyfi:backyard@127.0.0.1"),
            ]:
                await loop.sock_sendto(udp, query, ("127.0.0.1", responder.port))
                async with asyncio.timeout(5):
                    reply, _ = await loop.sock_recvfrom(udp, 256)
                assert reply == expected
            await loop.sock_sendto(udp, b"skyfi:other?", ("127.0.0.1", responder.port))
            await loop.sock_sendto(udp, b"hello", ("127.0.0.1", responder.port))
            with pytest.raises(TimeoutError):
                async with asyncio.timeout(0.3):
                    await loop.sock_recvfrom(udp, 256)
        assert responder.answered == 2


def stellarium_reads_ra(buffer: bytes) -> tuple[float, bytes]:
    """Stellarium's Lx200CommandGetRa: skip one leading '#', then HH:MM:SS# exactly."""
    if buffer[:1] == b"#":
        buffer = buffer[1:]
    text, rest = buffer[:9], buffer[9:]
    assert text[2:3] == b":"
    assert text[5:6] == b":"
    assert text[8:9] == b"#"
    return int(text[:2]) + int(text[3:5]) / 60 + int(text[6:8]) / 3600, rest


def stellarium_reads_dec(buffer: bytes) -> tuple[float, bytes]:
    """Stellarium's Lx200CommandGetDec: sign, DD, 0xDF, MM, ':', SS, '#' (anything but 0xDF
    after the degrees makes it log "error: degree sign expected" on every poll)."""
    if buffer[:1] == b"#":
        buffer = buffer[1:]
    text, rest = buffer[:10], buffer[10:]
    assert text[:1] in (b"+", b"-")
    assert text[3:4] == b"\xdf"
    assert text[6:7] == b":"
    assert text[9:10] == b"#"
    value = int(text[1:3]) + int(text[4:6]) / 60 + int(text[7:9]) / 3600
    return (-value if text[:1] == b"-" else value), rest


async def test_a_stellarium_shaped_session() -> None:
    """The bytes Stellarium's direct LX200 client writes, read back the way it reads them."""
    mount = simulated_mount()
    async with serving(mount) as (_, client):
        await client.send(b"#:GR#")
        await client.send(b"#:GD#")
        async with asyncio.timeout(5):
            buffer = await client.reader.readuntil(b"#") + await client.reader.readuntil(b"#")
        ra, buffer = stellarium_reads_ra(buffer)
        dec, buffer = stellarium_reads_dec(buffer)
        assert buffer == b""
        assert separation((ra, dec), jnow_of(mount)) < TOLERANCE_DEG
        # goto: Stellarium's own bytes, ":Sr HH:MM:SS#" and ":Sd sDD<0xDF>MM:SS#"
        target = jnow_up_in_the_south(mount, 50.0)
        await client.set_target(*target, degree=b"\xdf")
        assert await client.char(b":MS#") == b"0"
        await mount.wait_for(lambda s: not s.slewing, timeout_s=15)
        # sync: Stellarium takes the first byte as the status, the '#' is skipped later
        assert await client.char(b":CM#") == b"0"
        await client.send(b"#:GR#")
        async with asyncio.timeout(5):
            buffer = await client.reader.readuntil(b"#")
            buffer += await client.reader.readuntil(b"#")
        ra, buffer = stellarium_reads_ra(buffer)
        assert buffer == b""
        assert abs(ra - target[0]) < 0.001
        await client.send(b"#:GD#")
        async with asyncio.timeout(5):
            buffer = await client.reader.readuntil(b"#")
        dec, buffer = stellarium_reads_dec(buffer)
        assert buffer == b""
        assert abs(dec - target[1]) < 0.001
        await client.send(b"#:Q#")
        assert await client.nothing_more()


def degree_byte(reply: bytes, digits: int = 2) -> bytes:
    """The byte after the sign and the degrees of ``sDD?MM...#`` (or ``DDD?MM...#``)."""
    start = 1 if reply[:1] in (b"+", b"-") else 0
    return reply[start + digits : start + digits + 1]


async def test_each_client_is_answered_with_the_degree_sign_it_writes() -> None:
    """Meade's 0xDF until a client writes its own: SkySafari's '*' (`:St+37*17#`) gets '*' back
    on that connection only, Stellarium's 0xDF keeps 0xDF, INDI's ':' changes nothing."""
    mount = simulated_mount(rate=1.0)
    async with LX200Server(mount) as server:
        host, port = await server.on_tcp(port=0)
        stellarium, skysafari, indi = [
            Client(*await asyncio.open_connection(host, port)) for _ in range(3)
        ]
        try:
            for client in (stellarium, skysafari, indi):  # before any set command: Meade's byte
                assert degree_byte(await client.text(b":GD#")) == b"\xdf"
                assert degree_byte(await client.text(b":Gt#")) == b"\xdf"
            assert await skysafari.char(b":St+37*17#") == b"1"
            assert await skysafari.char(b":Sd+45*22:52#") == b"1"
            assert await stellarium.char(b":Sd +45\xdf22:52#") == b"1"
            assert await indi.char(b":Sd +45:22:52#") == b"1"
            assert await indi.char(b":St+37:17:00#") == b"1"
            for command, digits in [
                (b":GD#", 2),
                (b":Gd#", 2),
                (b":GA#", 2),
                (b":GZ#", 3),
                (b":Gt#", 2),
                (b":Gg#", 3),
            ]:
                assert degree_byte(await skysafari.text(command), digits) == b"*", command
                assert degree_byte(await stellarium.text(command), digits) == b"\xdf", command
                assert degree_byte(await indi.text(command), digits) == b"\xdf", command
            # what each reads back is what it set (INDI's f_scansexa takes any separator)
            assert (await indi.text(b":Gd#"))[:-1].decode("latin-1") == "+45\xdf22:52"
            assert (await skysafari.text(b":Gt#"))[:-1] == b"+37*17"
            # low precision keeps the client's sign too
            await skysafari.send(b":U#")
            assert degree_byte(await skysafari.text(b":GD#")) == b"*"
            # SkySafari switching to Meade's byte is followed
            assert await skysafari.char(b":Sd+45\xdf22#") == b"1"
            assert degree_byte(await skysafari.text(b":GD#")) == b"\xdf"
        finally:
            for client in (stellarium, skysafari, indi):
                client.writer.close()
                await client.writer.wait_closed()


async def test_each_client_is_answered_in_the_precision_it_writes() -> None:
    """A client writing minutes only (INDI in its short format: `:Sd +45*22#`) is answered in low
    precision; writing seconds again switches back; `:U#` still toggles in between."""
    mount = simulated_mount(rate=1.0)
    async with serving(mount) as (_, client):
        assert len(await client.text(b":GR#")) == len(b"HH:MM:SS#")
        assert await client.char(b":Sr 05:35.3#") == b"1"
        low_ra = await client.text(b":GR#")
        assert low_ra[5:6] == b".", low_ra
        assert len(low_ra) == len(b"HH:MM.T#"), low_ra
        assert await client.char(b":Sd +45*22#") == b"1"
        assert len(await client.text(b":GD#")) == len(b"sDD*MM#")
        assert (await client.text(b":Gd#"))[:-1] == b"+45*22"
        await client.send(b":U#")
        assert len(await client.text(b":GD#")) == len(b"sDD*MM:SS#")
        await client.send(b":U#")
        assert await client.char(b":Sd +45:22:52#") == b"1"  # INDI's long form: high again
        assert len(await client.text(b":GD#")) == len(b"sDD*MM:SS#")
        assert len(await client.text(b":GR#")) == len(b"HH:MM:SS#")
