"""How fast ``scopelink`` starts: ``--help``, ``--version`` and ``status --help`` against a bare
interpreter (``python -c pass``), best of N fresh processes each, measured in the same run.

Goal (issue #13 part 5): each within 10x ``python -c pass``.

    .venv/bin/python -m bench.startup              # best of 20 runs each
    .venv/bin/python -m bench.startup --quick      # best of 2 (smoke test)
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

from bench.provenance import provenance

GOAL_RATIO = 10.0
COMMANDS: tuple[tuple[str, ...], ...] = (("--help",), ("--version",), ("status", "--help"))


def best_of(command: Sequence[str], env: dict[str, str], runs: int) -> float:
    """The fastest of ``runs`` wall-clock runs of ``command`` (which must exit 0), in seconds."""
    best = float("inf")
    for _ in range(runs):
        started = time.perf_counter()
        subprocess.run(command, env=env, stdout=subprocess.DEVNULL, check=True, timeout=60)
        best = min(best, time.perf_counter() - started)
    return best


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="best of 2 runs each")
    parser.add_argument("--runs", type=int, default=20, metavar="N", help="runs each (default 20)")
    args = parser.parse_args(argv)
    runs = 2 if args.quick else args.runs
    python = sys.executable
    with tempfile.TemporaryDirectory() as folder:
        env = {**os.environ, "SCOPELINK_CONFIG": str(Path(folder) / "absent.toml")}
        floor = best_of([python, "-c", "pass"], env, runs)
        rows = [("python -c pass (peer)", floor)]
        for extra in COMMANDS:
            seconds = best_of([python, "-m", "scopelink", *extra], env, runs)
            rows.append(("scopelink " + " ".join(extra), seconds))
    for line in provenance():
        print(line)
    print(f"best of {runs} run(s) each, wall clock; goal: each within {GOAL_RATIO:g}x the peer")
    print(f"{'command':<28} {'ms':>8}  vs python -c pass")
    for label, seconds in rows:
        print(f"{label:<28} {seconds * 1000:>8.1f}  {seconds / floor:.1f}x")
    worst = max(seconds for _, seconds in rows[1:]) / floor
    verdict = "PASS" if worst <= GOAL_RATIO else "MISS"
    print(f"goal: {verdict}, slowest {worst:.1f}x the peer (goal <= {GOAL_RATIO:g}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
