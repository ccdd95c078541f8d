"""What durability costs: an atomic, fsynced write against a plain write of the same bytes.

Measured on the files scopelink keeps: the settings file (the commented example, ~1 KB, also
through the whole ``scopelink config set`` path: read, tomlkit edit, check with the reader,
atomic write), the Sky Commander's object store (59 slots, ~3 KB) and Alpaca's UniqueID (~50 B).
Peers measured in the same run and directory: ``Path.write_bytes`` (no fsync, not atomic: what a
crash can tear) and write + fsync in place (durable but not atomic). The atomic write adds a
rename and a directory fsync to the second.

    .venv/bin/python -m bench.persistence            # 200 writes each, in a temporary directory
    .venv/bin/python -m bench.persistence --quick    # 3 writes each (smoke test)
    .venv/bin/python -m bench.persistence --dir /mnt/sdcard   # on the disk you care about

The ``kill -9`` soak is the test itself with more kills per writer:
``SCOPELINK_KILLS=500 .venv/bin/pytest tests/reliability/test_persistence_kill.py -s``.
"""

from __future__ import annotations

import argparse
import io
import json
import os
import statistics
import tempfile
import time
from collections.abc import Callable
from contextlib import redirect_stdout
from pathlib import Path

from bench.provenance import print_provenance
from scopelink.cli.config_command import EXAMPLE_CONFIG
from scopelink.cli.main import main as scopelink_main
from scopelink.links.storage import write_atomically


def _plain(path: Path, data: bytes) -> None:
    path.write_bytes(data)


def _fsynced_in_place(path: Path, data: bytes) -> None:
    with open(path, "wb") as file:
        file.write(data)
        file.flush()
        os.fsync(file.fileno())


def _medians_us(writes: list[Callable[[int], None]], runs: int) -> list[tuple[float, float]]:
    """(best, median) time of each write in µs; interleaved run by run, so the disk's mood (other
    processes' flushes) weighs on every contender alike. The median is the figure a user sees
    (a write's cost varies with the disk); the best, what the code costs undisturbed."""
    times: list[list[float]] = [[] for _ in writes]
    for index in range(runs):
        for write, spent in zip(writes, times, strict=True):
            started = time.perf_counter()
            write(index)
            spent.append(time.perf_counter() - started)
    return [(min(spent) * 1e6, statistics.median(spent) * 1e6) for spent in times]


def _writing(
    writer: Callable[[Path, bytes], None], path: Path, data: bytes
) -> Callable[[int], None]:
    return lambda _: writer(path, data)


def _files() -> dict[str, bytes]:
    slots = {f"{n:02d}": [n * 0.25 % 24, n - 29.0] for n in range(59)}
    return {
        "settings file": EXAMPLE_CONFIG.encode(),
        "object store (59 slots)": json.dumps({"slots": slots}, indent=1).encode(),
        "UniqueID": b'{"UniqueID": "7b0c9c3e-5d0a-4c55-9a5f-1f1f8d2a6c11"}\n',
    }


def run(directory: Path, runs: int) -> None:
    print_provenance()
    print(f"median (best) per write, {runs} writes each, in {directory}")
    print(
        f"{'file':26} {'bytes':>6} {'plain µs':>13} {'fsync µs':>13} {'atomic µs':>13}"
        "  atomic/fsync (medians, bests)"
    )
    for name, data in _files().items():
        writers = (_plain, _fsynced_in_place, write_atomically)
        figures = _medians_us(
            [_writing(writer, directory / f"{n}.bin", data) for n, writer in enumerate(writers)],
            runs,
        )
        cells = " ".join(f"{median:6.0f} ({best:4.0f})" for best, median in figures)
        (_, _), (fsync_best, fsync_median), (atomic_best, atomic_median) = figures
        print(
            f"{name:26} {len(data):6d} {cells}  {atomic_median / fsync_median:5.2f}x "
            f"{atomic_best / fsync_best:5.2f}x"
        )
    config = directory / "config.toml"
    config.write_text(EXAMPLE_CONFIG, encoding="utf-8")
    os.environ["SCOPELINK_CONFIG"] = str(config)

    def config_set(index: int) -> None:
        with redirect_stdout(io.StringIO()):
            status = scopelink_main(["config", "set", "site.elevation", str(index)])
        assert status == 0

    (whole_best, whole), (alone_best, atomic_alone) = _medians_us(
        [
            config_set,
            lambda _: write_atomically(directory / "atomic.toml", EXAMPLE_CONFIG.encode()),
        ],
        runs,
    )
    print(
        f"'scopelink config set' in process: median {whole:.0f}µs (best {whole_best:.0f}µs), "
        f"{whole / atomic_alone:.2f}x its atomic write alone ({atomic_alone:.0f}µs, best "
        f"{alone_best:.0f}µs)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="3 writes each (smoke test)")
    parser.add_argument("--runs", type=int, default=200)
    parser.add_argument("--dir", type=Path, help="where to write (default: a temporary dir)")
    args = parser.parse_args()
    runs = 3 if args.quick else args.runs
    if args.dir is not None:
        args.dir.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=args.dir) as directory:
            run(Path(directory), runs)
    else:
        with tempfile.TemporaryDirectory() as directory:
            run(Path(directory), runs)


if __name__ == "__main__":
    main()
