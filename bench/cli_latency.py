"""How long a ``scopelink`` command takes from the shell, against its floors.

Each command is run as a user runs it (a fresh ``python -m scopelink`` process) and timed wall
clock, N runs: the best (the least disturbed by a shared machine, what every ratio uses) and
the median. Peers measured in the same run: a bare interpreter (``python -c pass``)
and the import of the CLI alone. For ``status`` over a 9600-baud-paced SynScan emulator the wire
time of the bytes exchanged (counted from the ``-v`` byte trace, 10 bits per byte) is the floor
the link itself sets.

    .venv/bin/python -m bench.cli_latency            # 5 runs each, best and median
    .venv/bin/python -m bench.cli_latency --quick    # 1 run each (smoke test)
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import re
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import NamedTuple

from bench.provenance import print_provenance

BITS_PER_BYTE = 10  # 8N1
BAUD = 9600
_TRACE_BYTES = re.compile(r"scopelink\.links\.trace:? .* (?:-->|<--) (\d+) bytes:")


def _environment(config: Path) -> dict[str, str]:
    return {**os.environ, "SCOPELINK_CONFIG": str(config), "PYTHONUNBUFFERED": "1"}


def _timed(command: Sequence[str], env: dict[str, str]) -> tuple[float, str]:
    started = time.perf_counter()
    result = subprocess.run(
        command, env=env, capture_output=True, text=True, check=False, timeout=120
    )
    elapsed = time.perf_counter() - started
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {result.stderr}")
    return elapsed, result.stderr


class Timing(NamedTuple):
    best: float
    median: float

    @classmethod
    def of(cls, times: Sequence[float]) -> Timing:
        return cls(min(times), statistics.median(times))


def _runs(command: Sequence[str], env: dict[str, str], runs: int) -> Timing:
    return Timing.of([_timed(command, env)[0] for _ in range(runs)])


def _runs_in_process(argv: list[str], env: dict[str, str], runs: int) -> Timing:
    """``scopelink ARGV`` through :func:`main` in this (warm) process: the command's own cost."""
    from scopelink.cli.main import main as scopelink_main

    saved = os.environ.get("SCOPELINK_CONFIG")
    os.environ["SCOPELINK_CONFIG"] = env["SCOPELINK_CONFIG"]
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            scopelink_main(argv)  # warm-up: first-use costs belong to start-up
            times = []
            for _ in range(runs):
                started = time.perf_counter()
                if scopelink_main(argv) != 0:
                    raise RuntimeError(f"scopelink {' '.join(argv)} failed")
                times.append(time.perf_counter() - started)
    finally:
        if saved is None:
            del os.environ["SCOPELINK_CONFIG"]
        else:
            os.environ["SCOPELINK_CONFIG"] = saved
    return Timing.of(times)


@contextmanager
def _paced_emulator(env: dict[str, str]) -> Iterator[str]:
    process = subprocess.Popen(
        [sys.executable, "-m", "scopelink", "emulate", "synscan", "--tcp", "127.0.0.1:0"],
        stdout=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
        text=True,
        env=env,
    )
    try:
        assert process.stdout is not None
        line = process.stdout.readline()
        match = re.search(r"listening on (127\.0\.0\.1:\d+)", line)
        if not match:
            raise RuntimeError(f"the emulator printed {line!r}")
        yield f"synscan:tcp://{match.group(1)}"
    finally:
        process.send_signal(signal.SIGTERM)
        process.wait(timeout=10)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one run each")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args(argv)
    runs = 1 if args.quick else args.runs
    python = sys.executable
    scopelink = [python, "-m", "scopelink"]
    with tempfile.TemporaryDirectory() as folder:
        env = _environment(Path(folder) / "absent.toml")
        floor_timing = _runs([python, "-c", "pass"], env, runs)
        floor = floor_timing.best
        rows: list[tuple[str, Timing, str]] = [("python -c pass (peer)", floor_timing, "1.0x")]
        imports = _runs([python, "-c", "import scopelink.cli.main"], env, runs)
        rows.append(("import scopelink.cli.main", imports, f"{imports.best / floor:.1f}x"))
        for label, extra in (
            ("scopelink --version", ["--version"]),
            ("scopelink status --device sim", ["status", "--json", "--device", "sim"]),
        ):
            timing = _runs([*scopelink, *extra], env, runs)
            rows.append((label, timing, f"{timing.best / floor:.1f}x"))
        with _paced_emulator(env) as device:
            status = [*scopelink, "status", "--json", "--device", device]
            timing = _runs(status, env, runs)
            _, trace = _timed([*status, "-v"], env)
            wire_bytes = sum(int(count) for count in _TRACE_BYTES.findall(trace))
            if not wire_bytes:
                raise RuntimeError("`scopelink status -v` printed no byte trace to count")
            wire_s = wire_bytes * BITS_PER_BYTE / BAUD
            rows.append(
                (
                    "scopelink status, SynScan emulator at 9600 baud",
                    timing,
                    f"{timing.best / floor:.1f}x; wire floor {wire_s * 1000:.0f} ms "
                    f"({wire_bytes} bytes): {timing.best / wire_s:.1f}x",
                )
            )
            in_process = _runs_in_process(["status", "--json", "--device", device], env, runs)
            rows.append(
                (
                    "  the same in a warm process (no start-up)",
                    in_process,
                    f"wire floor {wire_s * 1000:.0f} ms: {in_process.best / wire_s:.1f}x",
                )
            )
    print_provenance()
    print(f"best and median of {runs} run(s), wall clock; ratios of the best")
    print(f"{'command':<50} {'best s':>8} {'median s':>8}  vs python -c pass")
    for label, timing, ratio in rows:
        print(f"{label:<50} {timing.best:>8.3f} {timing.median:>8.3f}  {ratio}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
