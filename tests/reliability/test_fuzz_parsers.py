"""Fuzzing every parser, the fast subset: the checks of `bench.fuzz` under hypothesis (a few
hundred examples per parser), the benchmark's own quick run, and regression tests for what the
long run found. The million-input run is ``.venv/bin/python -m bench.fuzz``
(docs/reliability-fuzzing.md)."""

from __future__ import annotations

import asyncio
import json
import random
from pathlib import Path
from urllib.parse import quote_from_bytes

import pytest
from bench.fuzz import generate
from bench.fuzz_targets import (
    TARGETS,
    FuzzFailureError,
    Target,
    check_commander_server,
    check_synscan_server,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scopelink.cli.config import ConfigError, load_config
from scopelink.links import memory_pair
from scopelink.protocol import skytracker
from scopelink.protocol.synscan import (
    Ack,
    CommandParser,
    DateTime,
    Echo,
    EchoReply,
    Location,
    SetLocation,
    SetTime,
    SynScanClientConnection,
)
from scopelink.protocol.synscan import AnyCommand as SynScanCommand
from scopelink.servers.synscan.device import SynScanHandControl
from scopelink.servers.synscan.server import SynScanServer
from scopelink.web.params import BadRequestError, Body
from tests.support.alpaca import API, read_reply, serve, sim_mount
from tests.support.quick_bench import run_quick_bench
from tests.support.synscan import ask
from tests.support.web import served

EXAMPLES = 150


def fuzz_inputs(target: Target) -> st.SearchStrategy[bytes]:
    """Random bytes, or the benchmark's generator (mutated and chained seeds) driven by
    hypothesis, so a failure shrinks."""
    generated = st.randoms(use_true_random=False).map(lambda rng: generate(target, rng))
    return st.one_of(st.binary(max_size=min(target.max_size, 300)), generated)


@pytest.mark.parametrize("target", TARGETS, ids=[target.name for target in TARGETS])
def test_parser_never_crashes_and_keeps_its_invariants(target: Target) -> None:
    @settings(
        max_examples=EXAMPLES,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    )
    @given(fuzz_inputs(target), st.randoms(use_true_random=False))
    def fuzz(data: bytes, rng: random.Random) -> None:
        target.check(data, rng)

    fuzz()


def test_every_parser_the_brief_names_has_a_target() -> None:
    names = {target.name for target in TARGETS}
    assert names >= {
        "synscan-server",
        "synscan-client",
        "skytracker-server",
        "skytracker-client",
        "commander-server",
        "commander-client",
        "lx200-server",
        "stellarium-server",
        "stellarium-client",
        "alpaca-params",
        "alpaca-http",
        "dashboard-params",
        "decode-trace-text",
        "config",
    }


@pytest.mark.timeout(120)
def test_quick_fuzz_run_finds_nothing() -> None:
    result = run_quick_bench("bench.fuzz", timeout_s=120)
    lines = result.stdout.splitlines()
    assert any(line.startswith("alpaca-http") for line in lines), result.stdout
    total = next(line for line in lines if line.startswith("total "))
    assert " 0 crashes, hangs or broken invariants" in total, result.stdout
    assert any(line.startswith("slowest input:") for line in lines), result.stdout


def test_the_checks_catch_a_parser_that_loses_step(monkeypatch: pytest.MonkeyPatch) -> None:
    # The checks can fail: with a SynScan parser whose pause forgets nothing, the valid commands
    # sent after garbage are read as the garbage's payload, and the check says so.
    def keep_everything(self: CommandParser) -> bytes:
        return b""

    monkeypatch.setattr(CommandParser, "discard_partial", keep_everything)
    with pytest.raises(FuzzFailureError, match="after the pause"):
        check_synscan_server(b"r0000", random.Random(3))


_LEFT_OUT = {"slewtocoordinates", "slewtotarget", "slewtoaltaz", "connected", "disconnect"}
"""Synchronous slews wait for the slew to end (their async twins plus a wait; left out to stay
fast); the connection stays up so every member gets past its connection check."""

_ALPACA_PARAMETERS = [
    "Action",
    "Altitude",
    "Axis",
    "Azimuth",
    "Connected",
    "Declination",
    "Direction",
    "Duration",
    "Rate",
    "RightAscension",
    "SiteElevation",
    "SiteLatitude",
    "SiteLongitude",
    "SlewSettleTime",
    "TargetDeclination",
    "TargetRightAscension",
    "Tracking",
    "TrackingRate",
    "UTCDate",
    "Parameters",
]
"""Every parameter the telescope's members read."""

_VALUES = Target(
    "alpaca-values",
    (b"12.5", b"-30", b"0", b"3", b"1e3", b"True", b"false", b"2026-11-23T00:00:00Z", b"nan"),
    lambda data, rng: None,
    b"+-.eE0123456789 :TZ",
    max_size=40,
)
"""Values to mutate (the generator of bench.fuzz; this target's check is never called)."""


def _fuzzed_form(rng: random.Random) -> bytes:
    """Every parameter a member may read, each with a mutated value, in a random order."""
    pairs = [(b"ClientTransactionID", str(rng.randrange(2**32)).encode())]
    for name in _ALPACA_PARAMETERS:
        spelt = name.lower() if rng.random() < 0.05 else name  # PUT names are case-sensitive
        pairs.append((spelt.encode(), generate(_VALUES, rng)))
    rng.shuffle(pairs)
    return b"&".join(
        quote_from_bytes(name).encode() + b"=" + quote_from_bytes(value).encode()
        for name, value in pairs
    )


@pytest.mark.timeout(60)
async def test_alpaca_server_answers_fuzzed_parameters_without_internal_errors(
    tmp_path: Path,
) -> None:
    # End to end over a real socket: mutated parameter values, as query strings and PUT bodies,
    # to every telescope member of a real AlpacaServer on the simulated mount. A handler that
    # raised would show as a 500 or as ASCOM's "internal error" driver error.
    rng = random.Random(2026)
    statuses: set[tuple[int, int]] = set()
    async with serve(sim_mount(), state_dir=tmp_path) as server:
        members = sorted(set(server.telescope.members) - _LEFT_OUT)
        reader, writer = await asyncio.open_connection("127.0.0.1", server.port)
        try:
            writer.write(_put(f"{API}/connected", b"Connected=True&ClientTransactionID=1"))
            assert (await read_reply(reader))[0] == 200
            for _ in range(300):
                name = rng.choice(members)
                form = _fuzzed_form(rng)
                member = server.telescope.members[name]
                if member.put is None or (member.get is not None and rng.random() < 0.5):
                    get = f"GET {API}/{name}?{form.decode()} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n"
                    writer.write(get.encode())
                else:
                    writer.write(_put(f"{API}/{name}", form))
                status, _, body = await read_reply(reader)
                assert status in (200, 400, 405), (name, form, status, body)
                if status == 200:
                    reply = json.loads(body)
                    assert not reply["ErrorMessage"].startswith("internal error"), (name, form)
                    statuses.add((status, reply["ErrorNumber"]))
            writer.write(f"GET {API}/connected HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
            status, _, body = await read_reply(reader)
            assert status == 200
            assert json.loads(body)["ErrorNumber"] == 0
        finally:
            writer.close()
    # The inputs reached the members: accepted values and refused ones (InvalidValue 0x401).
    assert {(200, 0), (200, 0x401)} <= statuses, statuses


def _put(path: str, body: bytes) -> bytes:
    head = (
        f"PUT {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        "Content-Type: application/x-www-form-urlencoded\r\n"
        f"Content-Length: {len(body)}\r\n\r\n"
    )
    return head.encode() + body


# ------------------------------------------------------------------------------ found by fuzzing


def test_sky_commander_pause_after_an_overlong_line_ends_the_skip() -> None:
    # bench.fuzz commander-server:2785: the 32 bytes of an over-long 'L' line were all reported
    # (LineTooLong) when the line went quiet; the pause must end the skip, or the next command
    # would be swallowed up to its CR.
    server = skytracker.CommanderServer()
    server.receive_data(b"L" + b"9" * 31)
    assert isinstance(server.next_event(), skytracker.LineTooLong)
    assert server.next_event() is skytracker.NEED_DATA
    server.discard_partial()
    server.receive_data(skytracker.LoadObject(99, 5.588, -5.391).encode() + b"O")
    assert server.next_event() == skytracker.LoadObject(99, 5.588, -5.391)
    assert server.next_event() == skytracker.ReadOffsets()
    check_commander_server(b"80L96L03 .2. 9.1 +8.0 7+229.03809.", random.Random(1))


async def test_dashboard_refuses_deep_nesting_and_huge_integers_with_a_400() -> None:
    # bench.fuzz dashboard-params: json.loads raised RecursionError on "[[[[...", and float()
    # OverflowError on a 400-digit integer; both escaped as 500s.
    async with served() as s:
        for raw, words in (
            (b"[" * 3000, "nests too deeply"),
            (b'{"ra_hours": 1' + b"0" * 400 + b', "dec_deg": 0}', "'ra_hours' must lie in"),
        ):
            async with s.http.post(
                "/api/goto", data=raw, headers={"Content-Type": "application/json"}
            ) as response:
                assert response.status == 400, raw[:20]
                assert words in (await response.json())["error"]
        assert not (await s.mount.refresh()).slewing
    with pytest.raises(BadRequestError, match="must lie in"):
        Body({"alt_deg": -(10**400)}).number("alt_deg", -90.0, 90.0)


@pytest.mark.parametrize(
    ("text", "words"),
    [
        ("horizon = " + "[" * 2000, "nested too deeply"),
        ("[site]\nlatitude = " + "{ a = " * 2000, "nested too deeply"),
        ("[site]\nlatitude = 1" + "0" * 5000 + "\nlongitude = 0", "not valid TOML"),
        ("[site]\nlatitude = 1" + "0" * 400 + "\nlongitude = 0", "site.latitude"),
        ("[limits]\nmax_altitude = -1" + "0" * 400, "limits.max_altitude"),
        ("[horizon]\nprofile = [[0, 1" + "0" * 400 + "]]", "horizon.profile[0]"),
        ("[horizon]\nprofile = [[0, inf]]", "horizon.profile[0]"),
    ],
)
def test_config_reader_names_the_file_for_every_bad_file(
    tmp_path: Path, text: str, words: str
) -> None:
    # bench.fuzz config: tomllib's RecursionError and its 4300-digit ValueError escaped
    # load_config, and so did OverflowError on integers beyond any float.
    path = tmp_path / "config.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as raised:
        load_config(path)
    assert str(path) in str(raised.value)
    assert words in str(raised.value)


@pytest.mark.timeout(30)
@pytest.mark.parametrize(
    "command",
    [
        SetTime(DateTime(1, 2, 3, 103, 5, 2030, 10, True)),  # month 103
        SetTime(DateTime(76, 127, 3, 4, 61, 2030, 10, False)),  # hour 76, minute 127, day 61
        SetTime(DateTime(1, 2, 3, 4, 5, 2048, 44, True)),  # UTC+45: no such zone
        SetLocation(Location(100, 9, 0, False, 169, 181, 248, False)),  # latitude 100°
    ],
    ids=["month", "hour-minute-day", "zone", "latitude"],
)
async def test_synscan_hand_control_refuses_impossible_time_and_place_and_keeps_answering(
    command: SynScanCommand,
) -> None:
    # Fuzzing the hand control behind the parser: H and W bytes are passed through as sent
    # (docs/protocol-notes-synscan.md), and an impossible date or latitude raised ValueError out
    # of the device, ending the connection without a reply. The hand control acknowledges a
    # refused command with '#' and changes nothing.
    mount = sim_mount()
    pc, device = memory_pair()
    server = SynScanServer(SynScanHandControl(mount))
    await mount.connect()
    task = asyncio.create_task(server.serve(device))
    try:
        client = SynScanClientConnection()
        site, offset = mount.site, server.hand_control.clock_offset
        assert await ask(pc, client, command) == Ack()
        assert await ask(pc, client, Echo(0x81)) == EchoReply(0x81)
        assert mount.site == site
        assert server.hand_control.clock_offset == offset
    finally:
        await pc.close()
        await asyncio.wait_for(task, 5)
        await mount.disconnect()
