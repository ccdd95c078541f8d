"""Alpaca property-read throughput and latency under wrk, against a peer measured in the same run.

Runs ``wrk`` (Debian package ``wrk``) with 8 connections on ``GET .../telescope/0/rightascension``
against, one after the other on 127.0.0.1, in interleaved rounds (the best of each row counts):

1. scopelink's Alpaca server, in this process and without an access policy, in front of the
   simulated mount;
2. the same in front of the SynScan driver talking to ``scopelink emulate synscan`` (its own
   process, replies paced at 9600 baud 8N1) over TCP;
3. what ``scopelink serve --device sim:eq6`` gives out of the box: a child process with serve's
   defaults, its access policy included (wrk's 8 connections are one client address: its
   request-rate bucket paces them);
4. the same in front of the paced SynScan emulator, through a relay counting the line's bytes;
5. the peer: PyPI ``alpaca-simulators`` (FastAPI + uvicorn, exactly :data:`PEER_VERSION`) and its
   telescope simulator.

The serial line's use is measured, not assumed: the bytes the driver really moved each way during
the run (its link statistics in process, the relay's count for serve) over what 9600 baud 8N1
carries (960 B/s each way), and the bytes per poll the device sent (``L`` and ``e`` every poll,
``t`` and ``p`` only every tenth at rest) give the poll rate the line allows.

The peer lives in its own virtual environment (its FastAPI/uvicorn/cabaret dependencies stay out
of ours): ``--install-peer`` creates it under ``~/.cache/scopelink``; ``--peer PATH`` names another
``alpaca-simulators`` executable, refused unless its version is the pinned one (or
``--any-peer-version``, and then the report says so). The goal (issue #12), checked on rows 1 and 2
each: at least :data:`GOAL_RATIO` times the peer's throughput with p99 at most
:data:`GOAL_P99_MS` at 8 connections. Rows 3 and 4 have no throughput goal: serve's access policy
holds one address to its rate by design (``docs/reliability-security.md``).

Rows 1, 2 and the peer run on asyncio's default event loop (the peer's uvicorn is installed
without uvloop, as ``alpaca-simulators`` asks for it): servers compared on the same loop. Rows 3
and 4 are ``serve`` itself, on the loop it chooses (uvloop where installed, ``docs/serve.md``).

    .venv/bin/python -m bench.alpaca_wrk [--seconds 5] [--rounds 3] [--install-peer] [--quick]

See ``docs/benchmarks.md``.
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from dataclasses import dataclass, replace
from pathlib import Path

from bench.processes import Relay, alpaca_port, cpu_seconds, emulate, serve_alpaca, stop
from bench.provenance import peer_label, pin_problem, print_provenance
from scopelink.astro import Site
from scopelink.drivers.synscan import SynScanMount
from scopelink.mount import Mount
from scopelink.mount.polling import BITS_PER_BYTE, DEFAULT_MAX_POLL_BAUD
from scopelink.servers.access import DEFAULT_POLICY
from scopelink.servers.alpaca import AlpacaServer
from scopelink.sim import EQ6, SimulatedMount

SITE = Site(50.0, 10.0)
SITE_OPTION = f"{SITE.latitude_deg},{SITE.longitude_deg}"
CONNECTIONS = 8
THREADS = 2
PATH = "/api/v1/telescope/0/rightascension?ClientID=1&ClientTransactionID=1"
PEER_VERSION = "1.3.2"
"""The alpaca-simulators release measured against (pinned: its speed is part of the figure)."""
PEER_STACK = {
    "fastapi": "0.165.0",
    "uvicorn": "0.54.0",
    "starlette": "1.10.0",
    "pydantic": "2.14.4",
}
"""The peer's web stack, pinned at install and named in the report: its speed is the peer's."""
PEER_VENV = Path.home() / ".cache" / "scopelink" / f"alpaca-simulators-{PEER_VERSION}-venv"
GOAL_RATIO = 10.0
GOAL_P99_MS = 10.0
LINE_BAUD = 9600
"""The emulator's pacing, and serve's default ``max_poll_baud``."""
LINE_BYTES_PER_S = LINE_BAUD / BITS_PER_BYTE
assert LINE_BAUD == DEFAULT_MAX_POLL_BAUD


@dataclass(frozen=True)
class WrkResult:
    requests: int
    requests_per_s: float
    p50_ms: float
    p99_ms: float
    errors: int


_UNITS_MS = {"us": 0.001, "ms": 1.0, "s": 1000.0}


def _latency_ms(text: str) -> float:
    match = re.fullmatch(r"([\d.]+)(us|ms|s)", text)
    if match is None:
        raise ValueError(f"unexpected wrk latency {text!r}")
    return float(match.group(1)) * _UNITS_MS[match.group(2)]


def parse_wrk(output: str) -> WrkResult:
    """The figures we use from wrk's ``--latency`` report."""
    rate = re.search(r"Requests/sec:\s+([\d.]+)", output)
    p50 = re.search(r"^\s+50%\s+(\S+)", output, re.MULTILINE)
    p99 = re.search(r"^\s+99%\s+(\S+)", output, re.MULTILINE)
    if rate is None or p50 is None or p99 is None:
        raise ValueError(f"cannot read wrk's report:\n{output}")
    errors = 0
    non_2xx = re.search(r"Non-2xx or 3xx responses:\s+(\d+)", output)
    if non_2xx:
        errors += int(non_2xx.group(1))
    sockets = re.search(
        r"Socket errors: connect (\d+), read (\d+), write (\d+), timeout (\d+)", output
    )
    if sockets:
        errors += sum(int(n) for n in sockets.groups())
    total = re.search(r"(\d+) requests in", output)
    return WrkResult(
        int(total.group(1)) if total else 0,
        float(rate.group(1)),
        _latency_ms(p50.group(1)),
        _latency_ms(p99.group(1)),
        errors,
    )


async def run_wrk(wrk: str, url: str, seconds: float) -> WrkResult:
    process = await asyncio.create_subprocess_exec(
        wrk,
        f"-t{THREADS}",
        f"-c{CONNECTIONS}",
        f"-d{max(1, round(seconds))}s",
        "--latency",
        url,
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.PIPE,
    )
    out, err = await process.communicate()
    if process.returncode != 0:
        raise RuntimeError(f"wrk failed: {err.decode()}")
    return parse_wrk(out.decode())


# --- the servers under test --------------------------------------------------------------------


@asynccontextmanager
async def scopelink_server(mount: Mount, state_dir: Path) -> AsyncIterator[AlpacaServer]:
    """Our Alpaca server in this process, without an access policy (the HTTP layer itself)."""
    async with AlpacaServer(mount, port=0, discovery_port=None, state_dir=state_dir) as server:
        await server.telescope.connect()
        yield server


@asynccontextmanager
async def paced_synscan(home: Path) -> AsyncIterator[tuple[Relay, int]]:
    """``scopelink emulate synscan`` (9600-baud paced) in its own process, as a real hand control
    is its own device (its CPU is not the server's), behind a relay counting the line's bytes;
    yields the relay and the port it listens on."""
    emulator, port = await emulate(home, "synscan", "--site", SITE_OPTION, "--mount", "eq6")
    relay = Relay(port)
    try:
        yield relay, await relay.start()
    finally:
        await relay.close()
        await stop(emulator)


@asynccontextmanager
async def synscan_rig(home: Path) -> AsyncIterator[SynScanMount]:
    """The SynScan driver in this process on TCP to the paced emulator, around the relay (its
    own link statistics count the bytes; the relay's CPU would be counted as the server's)."""
    async with paced_synscan(home) as (relay, _):
        mount = SynScanMount(f"tcp://127.0.0.1:{relay.device_port}", site=SITE)
        await mount.connect()
        try:
            yield mount
        finally:
            await mount.disconnect()


@asynccontextmanager
async def served(home: Path, device: str) -> AsyncIterator[tuple[str, int]]:
    """``scopelink serve`` out of the box in front of ``device``, its telescope connected (as a
    client does first: unconnected, every read is an Alpaca error); yields its URL and pid."""
    process, printed = await serve_alpaca(home, device, "--site", SITE_OPTION)
    try:
        base = f"http://127.0.0.1:{alpaca_port(printed)}"
        await _put(base, "/api/v1/telescope/0/connected", "Connected=True&ClientID=1")
        yield base, process.pid
    finally:
        await stop(process)


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


async def _wait_for_port(port: int, process: asyncio.subprocess.Process, timeout_s: float) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if process.returncode is not None:
            raise RuntimeError("alpaca-simulators exited at start")
        try:
            _, writer = await asyncio.open_connection("127.0.0.1", port)
        except OSError:
            await asyncio.sleep(0.2)
            continue
        writer.close()
        await writer.wait_closed()
        return
    raise RuntimeError(f"alpaca-simulators did not listen on port {port} within {timeout_s} s")


@asynccontextmanager
async def peer_server(executable: str) -> AsyncIterator[tuple[str, int]]:
    """alpaca-simulators on 127.0.0.1 and a free port, its telescope connected; yields its URL."""
    port = _free_port()
    with tempfile.TemporaryDirectory() as workdir:
        process = await asyncio.create_subprocess_exec(
            *(executable, "--host", "127.0.0.1", "--port", str(port)),
            cwd=workdir,
            stdout=asyncio.subprocess.DEVNULL,
            stderr=asyncio.subprocess.DEVNULL,
        )
        try:
            await _wait_for_port(port, process, 60.0)
            base = f"http://127.0.0.1:{port}"
            await _put(base, "/api/v1/telescope/0/connected", "Connected=True&ClientID=1")
            yield base, process.pid
        finally:
            process.terminate()
            try:
                await asyncio.wait_for(process.wait(), 10.0)
            except TimeoutError:
                process.kill()
                await process.wait()


async def _put(base: str, path: str, form: str) -> None:
    import aiohttp

    headers = {"Content-Type": "application/x-www-form-urlencoded"}
    async with (
        aiohttp.ClientSession() as session,
        session.put(base + path, data=form, headers=headers) as response,
    ):
        body = await response.json()
        if response.status != 200 or body.get("ErrorNumber"):
            raise RuntimeError(f"PUT {path} failed: {response.status} {body}")


def find_peer(explicit: str | None) -> str | None:
    if explicit:
        return explicit
    candidate = PEER_VENV / "bin" / "alpaca-simulators"
    if candidate.exists():
        return str(candidate)
    return shutil.which("alpaca-simulators")


def peer_versions(executable: str) -> dict[str, str]:
    """The versions of alpaca-simulators and of :data:`PEER_STACK` installed beside
    ``executable`` (its venv's Python); "unknown" where they cannot be read."""
    python = Path(executable).parent / "python"
    names = ["alpaca-simulators", *PEER_STACK]
    query = (
        "import importlib.metadata as m\n"
        f"for name in {names!r}:\n"
        "    try: print(m.version(name))\n"
        "    except m.PackageNotFoundError: print('not installed')"
    )
    try:
        done = subprocess.run(
            [str(python), "-c", query], capture_output=True, text=True, check=True, timeout=60
        )
        found = done.stdout.split()
    except (OSError, subprocess.SubprocessError):
        found = []
    return {name: found[i] if i < len(found) else "unknown" for i, name in enumerate(names)}


def stack_label(versions: dict[str, str]) -> str:
    """The peer's web stack as measured, a version other than the pinned one marked."""
    return ", ".join(
        f"{name} {versions[name]}" + ("" if versions[name] == pin else f" (pin {pin})")
        for name, pin in PEER_STACK.items()
    )


def install_peer() -> str:
    """Create the peer's own virtual environment and install alpaca-simulators into it, its web
    stack pinned too."""
    PEER_VENV.parent.mkdir(parents=True, exist_ok=True)
    subprocess.run([sys.executable, "-m", "venv", str(PEER_VENV)], check=True)
    pip = PEER_VENV / "bin" / "pip"
    pins = [f"{name}=={version}" for name, version in PEER_STACK.items()]
    subprocess.run(
        [str(pip), "install", "-q", f"alpaca-simulators=={PEER_VERSION}", *pins], check=True
    )
    return str(PEER_VENV / "bin" / "alpaca-simulators")


# --- the run -------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Measured:
    wrk: WrkResult
    cpu_us_per_request: float
    line: str = ""
    """What the serial line carried during the run, for the rows with one."""


async def check_read(url: str) -> None:
    """One read of ``url`` must be an Alpaca success: wrk counts an HTTP 200 carrying an Alpaca
    error (not connected, say) as a request served."""
    import aiohttp

    async with aiohttp.ClientSession() as session, session.get(url) as response:
        body = await response.json()
        if response.status != 200 or body.get("ErrorNumber"):
            raise RuntimeError(f"GET {url} is not a reading: {response.status} {body}")


async def measure(wrk: str, url: str, seconds: float, pid: int | None = None) -> Measured:
    await check_read(url)
    cpu_before = cpu_seconds(pid)
    result = await run_wrk(wrk, url, seconds)
    cpu = cpu_seconds(pid) - cpu_before
    return Measured(result, 1e6 * cpu / max(result.requests, 1))


def line_use(sent: int, received: int, seconds: float, polls: int | None = None) -> str:
    """The line's use from the bytes really moved each way over ``seconds`` (and ``polls``)."""
    busier = max(sent, received) / seconds
    text = (
        f"line {busier / LINE_BYTES_PER_S:.0%} of {LINE_BAUD} 8N1 ({received / seconds:.0f} B/s in"
    )
    text += f", {sent / seconds:.0f} out)"
    if polls:
        per_poll = received / polls
        limit = LINE_BYTES_PER_S / per_poll
        text += (
            f", {polls / seconds:.1f} polls/s of {per_poll:.1f} B from the device: "
            f"{polls / seconds / limit:.2f} of the {limit:.1f}/s the line allows"
        )
    return text


async def measure_driver(wrk: str, url: str, seconds: float, driver: SynScanMount) -> Measured:
    """:func:`measure` with what the driver moved on its line meanwhile (its link statistics)."""
    statistics = driver.wire.statistics
    sent, received, polls = statistics.bytes_sent, statistics.bytes_received, driver.poller.polls
    started = time.monotonic()
    result = await measure(wrk, url, seconds)
    elapsed = time.monotonic() - started
    return replace(
        result,
        line=line_use(
            statistics.bytes_sent - sent,
            statistics.bytes_received - received,
            elapsed,
            driver.poller.polls - polls,
        ),
    )


async def measure_relayed(wrk: str, url: str, seconds: float, pid: int, relay: Relay) -> Measured:
    """:func:`measure` of a child process with what its device line carried (the relay's count)."""
    sent, received, started = relay.to_device, relay.from_device, time.monotonic()
    result = await measure(wrk, url, seconds, pid)
    elapsed = time.monotonic() - started
    return replace(
        result, line=line_use(relay.to_device - sent, relay.from_device - received, elapsed)
    )


def _best(results: list[Measured]) -> Measured | None:
    return max(results, key=lambda m: m.wrk.requests_per_s) if results else None


ROWS = (
    "scopelink Alpaca + simulated mount",
    "scopelink Alpaca + SynScan driver @9600",
    "scopelink serve (out of the box) + sim",
    "scopelink serve (out of the box) + SynScan @9600",
)


async def one_round(
    wrk: str, seconds: float, peer_executable: str | None, quick: bool, home: Path
) -> tuple[list[Measured | None], Measured | None]:
    """One run of every row (ours in ROWS order) and of the peer."""
    ours: list[Measured | None] = [None] * len(ROWS)
    peer = None
    async with scopelink_server(SimulatedMount(EQ6, site=SITE), home / "state") as server:
        ours[0] = await measure(wrk, server.url + PATH, seconds)
    if peer_executable is not None:
        async with peer_server(peer_executable) as (base, pid):
            peer = await measure(wrk, base + PATH, seconds, pid)
    if not quick:
        async with synscan_rig(home) as driver, scopelink_server(driver, home / "state") as server:
            await asyncio.sleep(0.5)
            ours[1] = await measure_driver(wrk, server.url + PATH, seconds, driver)
    async with served(home, "sim:eq6") as (base, pid):
        ours[2] = await measure(wrk, base + PATH, seconds, pid)
    if not quick:
        async with (
            paced_synscan(home) as (relay, port),
            served(home, f"synscan:tcp://127.0.0.1:{port}") as (base, pid),
        ):
            await asyncio.sleep(0.5)
            ours[3] = await measure_relayed(wrk, base + PATH, seconds, pid, relay)
    return ours, peer


def _row(name: str, result: Measured | None, peer: Measured | None, note: str = "") -> str:
    if result is None:
        return f"{name:<48} {'not run':>8}  {note}".rstrip()
    figures = result.wrk
    ratio = f"{figures.requests_per_s / peer.wrk.requests_per_s:7.1f}x" if peer else " no peer"
    return (
        f"{name:<48} {figures.requests_per_s:>8,.0f} {figures.p50_ms:>7.2f} {figures.p99_ms:>7.2f} "
        f"{figures.errors:>4} {result.cpu_us_per_request:>10.0f} {ratio}  {note or result.line}"
    ).rstrip()


def goal_lines(ours: list[Measured | None], peer: Measured | None) -> list[str]:
    """One verdict per row the goal speaks for (rows 1 and 2), PASS, MISS or not checked."""
    lines = []
    for name, row in zip(ROWS[:2], ours[:2], strict=True):
        claim = f"goal {name}: >= {GOAL_RATIO:g}x the peer, p99 <= {GOAL_P99_MS:g} ms: "
        if row is None:
            lines.append(claim + "not checked (row not run)")
        elif peer is None:
            lines.append(claim + f"not checked (no peer); p99 {row.wrk.p99_ms:.2f} ms")
        else:
            ratio = row.wrk.requests_per_s / peer.wrk.requests_per_s
            ok = ratio >= GOAL_RATIO and row.wrk.p99_ms <= GOAL_P99_MS
            lines.append(
                claim + f"{'PASS' if ok else 'MISS'} ({ratio:.1f}x, p99 {row.wrk.p99_ms:.2f} ms, "
                f"CPU per request {peer.cpu_us_per_request / row.cpu_us_per_request:.1f}x less)"
            )
    return lines


async def main_async(
    seconds: float, peer: tuple[str, str, str] | None, rounds: int, quick: bool
) -> int:
    # A poll in flight when a measured driver disconnects fails with a warning: not a finding.
    logging.getLogger("scopelink").setLevel(logging.ERROR)
    wrk = shutil.which("wrk")
    if wrk is None:
        print("wrk is not installed: apt-get install wrk", file=sys.stderr)
        return 2
    runs: list[list[Measured]] = [[] for _ in ROWS]
    peer_runs: list[Measured] = []
    with tempfile.TemporaryDirectory() as tmp:
        home = Path(tmp)
        (home / "state").mkdir()
        # Interleaved rounds, best of each: the machine is shared, and a burst of someone
        # else's load should not decide the ratio.
        for _ in range(rounds):
            ours, theirs = await one_round(wrk, seconds, peer[0] if peer else None, quick, home)
            for row_runs, run in zip(runs, ours, strict=True):
                if run is not None:
                    row_runs.append(run)
            if theirs is not None:
                peer_runs.append(theirs)
    best = [_best(row_runs) for row_runs in runs]
    best_peer = _best(peer_runs)
    label = peer_label("alpaca-simulators", peer[1], PEER_VERSION) if peer else "none (not run)"
    print_provenance(f"peer {label}" + (f"; {peer[2]}" if peer else ""))
    print(
        f"GET rightascension, wrk -t{THREADS} -c{CONNECTIONS}, {seconds:g} s per run, "
        f"each row the best of {rounds} interleaved round(s), 127.0.0.1"
    )
    print(
        "line: bytes the driver really moved during the run over 9600 baud 8N1 (960 B/s each "
        "way); polls/s against the rate those bytes per poll allow"
    )
    print(
        f"{'server':<48} {'req/s':>8} {'p50 ms':>7} {'p99 ms':>7} {'err':>4} "
        f"{'CPU us/req':>10} {'vs peer':>8}"
    )
    quick_note = "not in --quick"
    print(_row(ROWS[0], best[0], best_peer, "in process, no access policy"))
    print(_row(ROWS[1], best[1], best_peer, quick_note if quick else ""))
    policy = (
        f"serve's default policy: one address, {DEFAULT_POLICY.requests_per_s:g}/s "
        f"burst {DEFAULT_POLICY.burst}"
    )
    print(_row(ROWS[2], best[2], best_peer, policy))
    print(_row(ROWS[3], best[3], best_peer, quick_note if quick else ""))
    print(_row(f"{label} (peer)", best_peer, best_peer, "" if peer else "peer not run"))
    for line in goal_lines(best[:2], best_peer):
        print(line)
    print(f"{ROWS[2]}, {ROWS[3]}: no throughput goal ({policy})")
    return 0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0, help="wrk duration per server")
    parser.add_argument("--peer", help="path of an alpaca-simulators executable")
    parser.add_argument("--install-peer", action="store_true", help="pip-install the peer first")
    parser.add_argument("--no-peer", action="store_true", help="skip the peer")
    parser.add_argument(
        "--any-peer-version", action="store_true", help=f"accept a peer other than {PEER_VERSION}"
    )
    parser.add_argument("--rounds", type=int, default=3, help="interleaved rounds (best counts)")
    parser.add_argument(
        "--quick", action="store_true", help="1 s, 1 round, no SynScan and no peer (smoke test)"
    )
    args = parser.parse_args()
    seconds = 1.0 if args.quick else args.seconds
    peer = None
    if not (args.no_peer or args.quick):
        executable = install_peer() if args.install_peer else find_peer(args.peer)
        if executable is not None:
            versions = peer_versions(executable)
            version = versions["alpaca-simulators"]
            problem = pin_problem("alpaca-simulators", version, PEER_VERSION, args.any_peer_version)
            if problem is not None:
                print(f"bench.alpaca_wrk: {executable}: {problem}", file=sys.stderr)
                sys.exit(2)
            peer = (executable, version, stack_label(versions))
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    rounds = 1 if args.quick else max(1, args.rounds)
    sys.exit(asyncio.run(main_async(seconds, peer, rounds, args.quick)))


if __name__ == "__main__":
    main()
