"""``python -m bench.soak``: the command line (the night, or the ``--emulator`` role)."""

from __future__ import annotations

import argparse
import asyncio
import dataclasses
import sys

from bench.soak.config import FULL, QUICK
from bench.soak.report import print_report
from bench.soak.run import run_soak
from bench.soak.stack import emulate
from scopelink.links import precise_event_loop


def main() -> int:
    parser = argparse.ArgumentParser(
        prog="python -m bench.soak", description="a simulated night under load and faults"
    )
    parser.add_argument("--hours", type=float, default=FULL.hours, help="simulated hours")
    parser.add_argument("--rate", type=float, default=FULL.rate, help="simulated time speed-up")
    parser.add_argument("--seed", type=int, default=FULL.seed, help="faults and client choices")
    parser.add_argument("--quick", action="store_true", help="1 hour at x200 (the test's run)")
    parser.add_argument("--no-faults", action="store_true", help="the same night without faults")
    parser.add_argument("--emulator", action="store_true", help=argparse.SUPPRESS)  # the device
    args = parser.parse_args()
    if args.emulator:
        # Paced replies keep time on the precise loop, as in 'scopelink emulate'
        with asyncio.Runner(loop_factory=precise_event_loop) as runner:
            runner.run(emulate(args.rate, args.seed))
        return 0
    config = QUICK if args.quick else FULL
    if not args.quick:
        config = dataclasses.replace(config, hours=args.hours, rate=args.rate)
    config = dataclasses.replace(config, seed=args.seed, faults=not args.no_faults)
    report = asyncio.run(run_soak(config))
    print_report(report)
    return 0 if report.passed else 1


if __name__ == "__main__":
    sys.exit(main())
