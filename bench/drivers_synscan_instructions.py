"""Instructions per ``e`` of the clients of ``bench.drivers_synscan``, counted by valgrind.

CPU time per command moves by 20-50 % from run to run on a shared 2-core machine; the count of
user-space instructions a client runs per command does not (about ±2 %), so it tells whether a
change to the driver saved work even when the machine is busy. It leaves out the kernel (the
``send``/``recv``/``epoll_wait`` system calls, about half of the floor's CPU time) and cache
misses, so it ranks changes; the CPU table of ``bench.drivers_synscan`` judges the goal.

Each client runs in its own ``valgrind --tool=callgrind`` process for ``SHORT`` and ``LONG``
commands against one unpaced emulator (in another process, not counted); per command =
(long − short) / (LONG − SHORT), which cancels start-up and imports.

Run ``.venv/bin/python -m bench.drivers_synscan_instructions`` (a few minutes; needs valgrind).
See ``docs/benchmarks.md``, "SynScan driver".
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys

from bench.drivers_synscan import CLIENTS, emulator_process
from bench.provenance import print_provenance

SHORT, LONG = 200, 5200
_COLLECTED = re.compile(r"Collected : (\d+)")


def run_client(name: str, url: str, count: int) -> None:
    """In this process: connect client ``name`` and run ``count`` commands."""
    make = dict(CLIENTS)[name]
    make(url)(count)


def instructions(name: str, url: str, count: int) -> int:
    """User-space instructions of a process that runs ``count`` commands of client ``name``."""
    command = [
        "valgrind",
        "--tool=callgrind",
        "--callgrind-out-file=/dev/null",
        sys.executable,
        "-m",
        "bench.drivers_synscan_instructions",
        "--run",
        name,
        url,
        str(count),
    ]
    environment = dict(os.environ, PYTHONHASHSEED="0")
    result = subprocess.run(command, capture_output=True, text=True, env=environment, check=True)
    found = _COLLECTED.search(result.stderr)
    if found is None:
        raise RuntimeError(f"valgrind reported no count for {name}: {result.stderr[-500:]}")
    return int(found.group(1))


def main() -> int:
    if shutil.which("valgrind") is None:
        print("bench.drivers_synscan_instructions: valgrind is not installed", file=sys.stderr)
        return 2
    print_provenance("valgrind --tool=callgrind, user-space instructions")
    print(f"instructions per 'e' command ((run of {LONG} - run of {SHORT}) / {LONG - SHORT})")
    with emulator_process(paced_replies=False) as url:
        for name, _make in CLIENTS:
            per = (instructions(name, url, LONG) - instructions(name, url, SHORT)) / (LONG - SHORT)
            print(f"{name:<34} {per / 1000:>8.1f} k")
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] == ["--run"]:
        run_client(sys.argv[2], sys.argv[3], int(sys.argv[4]))
        sys.exit(0)
    sys.exit(main())
