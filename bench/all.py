"""Every benchmark, in the order and with the options ``docs/benchmarks.md`` documents.

    .venv/bin/python -m bench.all                  # everything but the hour-long memory run
    .venv/bin/python -m bench.all --long           # ... and the memory run (an hour more)
    .venv/bin/python -m bench.all --only astro alpaca_wrk
    .venv/bin/python -m bench.all --list           # the plan, run nothing

Each benchmark runs as ``python -m bench.NAME OPTIONS`` in its own process, one after the other
(never two at once: they would measure each other). Its report is shown as it runs and saved to
``OUT/NAME.txt`` (``--out``, default a new directory under the system's temporary directory);
the end is a summary: every report's exit status and time, and every goal line, the missed ones
marked. A benchmark not present (``bench/startup.py`` until it lands) is listed as skipped.

Run it on a quiet machine: the figures are for ``docs/benchmarks.md``, each section of which has a
line waiting for its report. Before the first run: ``python -m bench.alpaca_wrk --install-peer``
(the Alpaca peer in its own venv) and ``apt-get install wrk``.
"""

from __future__ import annotations

import argparse
import importlib.util
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path

from bench.provenance import provenance

ROOT = Path(__file__).resolve().parent.parent


@dataclass(frozen=True)
class Step:
    name: str
    """The report's file name, and what ``--only``/``--skip`` match (the module, or a variant)."""
    module: str
    options: tuple[str, ...] = ()
    long: bool = False
    """Only with ``--long``."""

    @property
    def command(self) -> str:
        """As docs/benchmarks.md shows it."""
        return " ".join(("python -m", f"bench.{self.module}", *self.options))


PLAN = (
    Step("emulators", "emulators"),
    Step("planetarium_servers", "planetarium_servers"),
    Step("web_dashboard", "web_dashboard"),
    Step("web_object_flood", "web_object_flood"),
    Step("cli_latency", "cli_latency"),
    Step("startup", "startup"),
    Step("alpaca_wrk", "alpaca_wrk"),
    Step("polling", "polling"),
    Step("drivers_skytracker", "drivers_skytracker"),
    Step("drivers_synscan", "drivers_synscan"),
    Step("fault_recovery_synscan", "fault_recovery_synscan"),
    Step("reconnect", "reconnect"),
    Step("astro", "astro"),
    Step("persistence", "persistence"),
    Step("pointing", "pointing"),
    Step("tracking", "tracking"),
    Step("security_flood", "security_flood"),
    Step("safety_guard", "safety_guard"),
    Step("safety_guard_noisy", "safety_guard", ("--noisy",)),
    Step("safety_guard_skytracker", "safety_guard", ("--skytracker", "--trials", "5")),
    Step("safety_sun", "safety_sun"),
    Step("safety_sun_noisy", "safety_sun", ("--noisy",)),
    Step("fuzz", "fuzz"),
    Step("soak", "soak"),
    Step("polling_memory", "polling", ("--memory", "--minutes", "60"), long=True),
)
"""The documented order: quick and CPU-bound first, the long runs last."""

GOAL = re.compile(r"^\s*goal\b|:\s*(PASS|MISS|met|MISSED)\b|^soak (PASSED|FAILED)")
"""A goal line: it starts with "goal", gives a verdict after a colon (bench.polling's rows), or
is the soak's verdict."""
MISSED = re.compile(r"\b(MISS|MISSED|FAILED)\b")


def present(step: Step) -> bool:
    return importlib.util.find_spec(f"bench.{step.module}") is not None


def chosen(only: list[str] | None, skip: list[str], long: bool) -> list[Step]:
    names = {step.name for step in PLAN}
    unknown = sorted((set(only or []) | set(skip)) - names)
    if unknown:
        raise SystemExit(f"bench.all: no benchmark named {', '.join(unknown)} (see --list)")
    return [
        step
        for step in PLAN
        if (step.name in only if only else not step.long or long) and step.name not in skip
    ]


@dataclass(frozen=True)
class Outcome:
    step: Step
    status: int | None
    """None: not present."""
    seconds: float
    goals: list[str]


def run_step(step: Step, out: Path) -> Outcome:
    if not present(step):
        return Outcome(step, None, 0.0, [])
    started = time.monotonic()
    origin = [f"{line}\n" for line in provenance()]
    lines: list[str] = []
    with subprocess.Popen(
        [sys.executable, "-m", f"bench.{step.module}", *step.options],
        cwd=ROOT,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    ) as process:
        assert process.stdout is not None
        for line in process.stdout:
            sys.stdout.write(line)
            sys.stdout.flush()
            lines.append(line)
    # A report that does not say where its figures come from gets it from here (taken as it
    # started): bench.soak and bench.fuzz print none of their own yet.
    head = [] if lines and lines[0].startswith("date ") else origin
    (out / f"{step.name}.txt").write_text("".join(head + lines), encoding="utf-8")
    goals = [line.rstrip("\n") for line in lines if GOAL.search(line)]
    return Outcome(step, process.returncode, time.monotonic() - started, goals)


def summary(outcomes: list[Outcome]) -> list[str]:
    lines = ["", "summary:"]
    for outcome in outcomes:
        if outcome.status is None:
            lines.append(
                f"  {outcome.step.command}: skipped (bench/{outcome.step.module}.py absent)"
            )
            continue
        missed = sum(bool(MISSED.search(goal)) for goal in outcome.goals)
        lines.append(
            f"  {outcome.step.command}: exit {outcome.status}, {outcome.seconds:.0f} s, "
            f"{len(outcome.goals)} goal line(s), {missed} missed"
        )
        lines.extend(
            f"    {'MISSED ' if MISSED.search(goal) else ''}{goal.strip()}"
            for goal in outcome.goals
        )
    return lines


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.all", description=__doc__)
    parser.add_argument("--only", nargs="+", metavar="NAME", help="only these (see --list)")
    parser.add_argument("--skip", nargs="+", metavar="NAME", default=[], help="all but these")
    parser.add_argument("--long", action="store_true", help="also the hour-long memory run")
    parser.add_argument("--out", type=Path, help="where the reports go (default: a new temp dir)")
    parser.add_argument("--list", action="store_true", help="print the plan and run nothing")
    args = parser.parse_args(argv)
    steps = chosen(args.only, args.skip, args.long)
    if args.list:
        for step in steps:
            absent = "" if present(step) else "  (absent: skipped)"
            print(f"{step.name:<24} {step.command}{'  [--long]' if step.long else ''}{absent}")
        return 0
    stamp = f"{datetime.now(UTC):%Y%m%d-%H%M}"
    out = args.out or Path(tempfile.mkdtemp(prefix=f"scopelink-bench-{stamp}-"))
    out.mkdir(parents=True, exist_ok=True)
    outcomes = []
    for step in steps:
        print(f"\n=== {step.command}  (report: {out / step.name}.txt)", flush=True)
        outcomes.append(run_step(step, out))
    report = summary(outcomes)
    (out / "summary.txt").write_text("\n".join(report) + "\n", encoding="utf-8")
    print("\n".join(report))
    print(f"reports in {out}")
    return 1 if any(outcome.status not in (0, None) for outcome in outcomes) else 0


if __name__ == "__main__":
    sys.exit(main())
