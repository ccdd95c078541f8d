"""``python -m bench.all`` runs every benchmark the docs document, in their order, and its summary
names every goal line, the missed ones marked (so the one command the figures come from cannot
drift from the benchmarks or from docs/benchmarks.md)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest
from bench.all import PLAN, Outcome, Step, present, summary

from tests.support.quick_bench import ROOT

DOCS = (ROOT / "docs" / "benchmarks.md").read_text(encoding="utf-8")


def test_every_benchmark_is_in_the_plan() -> None:
    benchmarks = {
        path.stem
        for path in (ROOT / "bench").glob("*.py")
        if 'if __name__ == "__main__"' in path.read_text(encoding="utf-8")
    } - {"all"}
    assert benchmarks <= {step.module for step in PLAN}


def _heading(step: Step) -> int:
    """Where the section of ``step``'s benchmark starts (a module, or a package)."""
    for name in (f"(`bench/{step.module}.py`)", f"(`bench/{step.module}/`)"):
        if name in DOCS:
            return DOCS.index(name)
    raise AssertionError(f"docs/benchmarks.md has no section for bench/{step.module}")


def test_the_docs_show_every_command_of_the_plan_in_its_order() -> None:
    positions = []
    for step in PLAN:
        if not present(step):  # a benchmark not written yet
            continue
        assert step.command in DOCS, step.command
        if not step.long:  # a long run is documented in its benchmark's section, run last
            positions.append(_heading(step))
    assert positions == sorted(positions), (
        "docs/benchmarks.md's sections are not in bench.all's order"
    )
    # Every section either waits for its figures from the command it names, or shows figures
    # with the commit they were measured on.
    for step in PLAN:
        if present(step) and not step.long and not step.options:
            start = _heading(step)
            end = DOCS.find("\n## ", start)
            section = DOCS[start : end if end != -1 else len(DOCS)]
            waiting = f"_pending: paste the report of `{step.command}` here" in section
            assert waiting or re.search(r"commit [0-9a-f]{7}", section), step.command


def test_the_summary_marks_every_missed_goal() -> None:
    step = Step("polling", "polling")
    goals = [
        "synscan     9600     none       0.010   12/s   21/s   2.2%  line <= 10%: met",
        "synscan     instant  none       0.150  300/s  900/s  93.8%  core <= 0.1: MISSED",
        "goal scopelink Alpaca + simulated mount: >= 10x the peer, p99 <= 10 ms: PASS (13.1x)",
    ]
    lines = summary(
        [Outcome(step, 1, 12.0, goals), Outcome(Step("startup", "startup"), None, 0, [])]
    )
    assert "  python -m bench.polling: exit 1, 12 s, 3 goal line(s), 1 missed" in lines
    assert sum(line.startswith("    MISSED ") for line in lines) == 1
    assert "  python -m bench.startup: skipped (bench/startup.py absent)" in lines


@pytest.mark.timeout(120)
def test_a_run_saves_each_report_with_its_provenance(tmp_path: Path) -> None:
    listed = subprocess.run(
        [sys.executable, "-m", "bench.all", "--list"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert listed.returncode == 0, listed.stderr
    assert [line.split()[0] for line in listed.stdout.splitlines()] == [
        step.name for step in PLAN if not step.long
    ]
    done = subprocess.run(
        [sys.executable, "-m", "bench.all", "--only", "persistence", "--out", str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=110,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    report = (tmp_path / "persistence.txt").read_text(encoding="utf-8")
    assert report.startswith("date "), report
    assert "python -m bench.persistence: exit 0" in (tmp_path / "summary.txt").read_text()
    unknown = subprocess.run(
        [sys.executable, "-m", "bench.all", "--only", "nope"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    assert unknown.returncode != 0
    assert unknown.stderr.strip() == "bench.all: no benchmark named nope (see --list)"


def test_the_docs_quote_the_pins_and_goals_the_code_checks() -> None:
    """docs/benchmarks.md and the benchmarks never disagree on a peer's version or a goal."""
    from bench import (
        alpaca_wrk,
        astro,
        drivers_skytracker,
        drivers_synscan,
        provenance,
        security_flood,
    )

    for peer, version in (
        ("`alpaca-simulators`", alpaca_wrk.PEER_VERSION),
        ("`astropy`", astro.PEER_PIN),
        ("`nexstar`", drivers_synscan.NEXSTAR_PIN),
        ("`uvloop`", provenance.UVLOOP_PIN),
    ):
        assert f"| PyPI {peer}" in DOCS, peer
        row = next(line for line in DOCS.splitlines() if line.strip().startswith(f"| PyPI {peer}"))
        assert f"| {version} |" in row, row
    stack = ", ".join(f"{name} {pin}" for name, pin in alpaca_wrk.PEER_STACK.items())
    assert f"| {stack} | `bench.alpaca_wrk` |" in DOCS
    text = " ".join(DOCS.split())  # as read, whatever the line breaks
    assert (
        f"at least **{alpaca_wrk.GOAL_RATIO:g}x the peer's throughput with p99 <= "
        f"{alpaca_wrk.GOAL_P99_MS:g} ms**"
    ) in text
    assert f"within **{drivers_skytracker.GOAL_CPU_OF_BARE:g}x**" in text
    assert f"Each of {drivers_skytracker.CPU_ROUNDS} rounds runs every row's driver block" in text
    rounds, commands = drivers_synscan.FULL.cpu_rounds, drivers_synscan.FULL.commands
    assert f"alternate for {rounds} rounds of {commands} commands" in text
    assert f"poller keeps **>= {100 * security_flood.GOAL_RATIO:.0f} %**" in text
    assert f"the best of {security_flood.FULL.rounds} rounds" in text
