"""The checks of a night and its report."""

from __future__ import annotations

import itertools
import statistics
from collections import Counter
from dataclasses import dataclass

from bench.soak.config import (
    DEVICE_MERIDIAN_TOLERANCE_DEG,
    FD_GROWTH_BOUND,
    FINAL_LANDING_BOUND_DEG,
    POLL_GAP_BOUND_S,
    QUIET_POLL_GAP_BOUND_S,
    QUIET_SETTLE_S,
    QUIET_WINDOW_MIN_S,
    RSS_GROWTH_FLOOR_MIB,
    RSS_GROWTH_MIB_PER_HOUR,
    SLEW_BOUND_S,
    STREAM_GAP_BOUND_S,
    SoakConfig,
)
from bench.soak.night import Night
from bench.soak.stack import MERIDIAN_STOP


@dataclass
class Check:
    name: str
    passed: bool
    detail: str


@dataclass
class SoakReport:
    config: SoakConfig
    night: Night
    checks: list[Check]
    baseline_files: Counter[str]
    """What serve held open before any client came (by kind, see :func:`open_files`)."""
    final_files: Counter[str]
    """What it held open a few seconds after the last client left."""
    exit_codes: tuple[int, int]

    @property
    def passed(self) -> bool:
        return all(check.passed for check in self.checks)


def _longest_gap(times: list[float], start: float, end: float) -> tuple[float, float]:
    """The longest stretch of [start, end] without any of ``times``: (length, its start)."""
    points = [start, *(t for t in times if start <= t <= end), end]
    return max((b - a, a) for a, b in itertools.pairwise(points))


def _longest_slewing_after_command(night: Night) -> tuple[float, str]:
    """The longest time Slewing stayed true after the latest motion command before it, and
    that command (what, when)."""
    longest, which = 0.0, "none"
    since: float | None = None
    for at, slewing in night.slewing_samples:
        if not slewing:
            since = None
            continue
        commanded, what = max(
            ((t, w) for t, w in night.motion_commands if t <= at), default=(0.0, "none")
        )
        since = at if since is None else since
        if at - max(since, commanded) > longest:
            longest = at - max(since, commanded)
            which = f"{what} at {commanded:.1f} s"
    return longest, which


def _quarters(values: list[tuple[float, int, int]], warm_up_s: float) -> tuple[list[int], ...]:
    settled = [v for v in values if v[0] >= warm_up_s]
    quarter = max(1, len(settled) // 4)
    first, last = settled[:quarter], settled[-quarter:]
    return [v[1] for v in first], [v[1] for v in last], [v[2] for v in first], [v[2] for v in last]


def fault_spans(night: Night, end: float) -> list[tuple[float, float]]:
    """(start, end) of every fault: a stall or halt ends when it is resumed, any other fault when
    it fires."""
    resumes = [at for at, line in night.fault_switches if line in {"resume", "clear"}]
    spans: list[tuple[float, float]] = []
    for at, kind in night.faults:
        ends = at
        if kind in {"stall", "halt"}:
            ends = min((t for t in resumes if t >= at), default=end)
        spans.append((at, ends))
    return spans


def quiet_windows(night: Night, end: float) -> list[tuple[float, float]]:
    """Stretches without faults, from ``QUIET_SETTLE_S`` after a fault ended to the next fault
    (or the end), long enough to judge."""
    windows: list[tuple[float, float]] = []
    quiet_from = 0.0
    for starts, ends in sorted(fault_spans(night, end)):
        if starts - quiet_from >= QUIET_WINDOW_MIN_S:
            windows.append((quiet_from, starts))
        quiet_from = max(quiet_from, ends + QUIET_SETTLE_S)
    if end - quiet_from >= QUIET_WINDOW_MIN_S:
        windows.append((quiet_from, end))
    return windows


def _recovery(night: Night, end: float) -> tuple[int, list[str], float]:
    """(quiet windows judged, those that did not recover, longest reading gap inside them)."""
    windows = quiet_windows(night, end)
    failures: list[str] = []
    worst = 0.0
    for a, b in windows:
        gap, gap_at = _longest_gap(night.reading_advances, a, b)
        worst = max(worst, gap)
        failed = [f for t, f in night.poll_failed_samples if a <= t <= b]
        if gap > QUIET_POLL_GAP_BOUND_S:
            failures.append(
                f"{a:.0f}-{b:.0f} s: a gap of {gap:.1f} s between readings from {gap_at:.1f} s"
            )
        if failed and all(failed):
            failures.append(f"{a:.0f}-{b:.0f} s: the failed poll stayed among the problems")
    return len(windows), failures, worst


def _files_text(files: Counter[str]) -> str:
    return ", ".join(f"{n}x {kind}" for kind, n in sorted(files.items())) or "nothing"


def judge(report: SoakReport) -> list[Check]:
    night, config = report.night, report.config
    end = config.real_s
    unanswered = [late for record in night.requests.values() for late in record.late]
    unanswered += night.broken
    spans = fault_spans(night, end)
    unanswered += [
        f"{what}: no answer outside a fault"
        for at, what in night.withheld
        if not any(start <= at <= ends + QUIET_SETTLE_S for start, ends in spans)
    ]
    gap, gap_at = _longest_gap(night.reading_advances, 1.0, end)
    gap_bound = POLL_GAP_BOUND_S + (config.outage_s if config.faults and config.outages else 0.0)
    windows, not_recovered, quiet_gap = _recovery(night, end)
    slewing_for, slewing_after = _longest_slewing_after_command(night)
    stream_gap = max(night.stream_gaps, default=0.0)
    rss_first, rss_last, fds_first, fds_last = _quarters(night.memory, warm_up_s=0.1 * end)
    rss_growth_mib = (statistics.median(rss_last) - statistics.median(rss_first)) / 1024
    settled = [(t, rss) for t, rss, _ in night.memory if t >= 0.1 * end]
    trend = statistics.linear_regression([t for t, _ in settled], [rss for _, rss in settled])
    trend_mib_per_hour = trend.slope * 3600 / 1024  # per real hour: the load runs in real time
    quarters_apart_h = 0.75 * (end - 0.1 * end) / 3600  # between the quarters' middles
    rss_bound_mib = max(RSS_GROWTH_FLOOR_MIB, RSS_GROWTH_MIB_PER_HOUR * quarters_apart_h)
    fd_growth = max(fds_last) - max(fds_first)
    took, miss = night.final_landing
    # The horizon guard's notice is a problem shown on purpose, not a failure to recover; so is
    # serve's meridian stop, judged on serve's clock while the device's sky runs `rate` times
    # faster (bench/soak/device_sky.py): the meridian limit is checked in the device's sky below.
    failures_after = [
        p for p in night.last_problems if "was stopped at" not in p and MERIDIAN_STOP not in p
    ]
    samples, excess_deg, worst = night.device_meridian
    kinds = {spec.split(":")[1] for spec in config.fault_specs()}
    if config.faults:
        kinds |= {spec.split(":")[1] for _, spec in config.scripted}
        kinds |= {kind for _, kind in config.outages}
    fired = {kind for _, kind in night.faults}
    left_open = report.final_files - report.baseline_files
    data_files = Counter({kind: n for kind, n in left_open.items() if kind.startswith("/")})
    left_open -= data_files
    return [
        Check(
            "every fault kind fired",
            fired == kinds,
            f"{len(night.faults)} faults; kinds never fired: "
            f"{', '.join(sorted(kinds - fired)) or 'none'}",
        ),
        Check(
            "no request unanswered, no connection broken",
            not unanswered,
            "; ".join(unanswered[:3])
            or "every request answered within its bound"
            + (
                f" ({len(night.withheld)} position reads withheld during faults: the reading "
                "was stale)"
                if night.withheld
                else ""
            ),
        ),
        Check(
            "no stuck slew",
            not night.stuck and slewing_for <= SLEW_BOUND_S,
            "; ".join(night.stuck[:3])
            or f"longest Slewing after a motion command {slewing_for:.1f} s <= {SLEW_BOUND_S:g} s "
            f"({slewing_after})",
        ),
        Check(
            "poller never stops",
            gap <= gap_bound,
            f"longest gap between readings {gap:.1f} s <= {gap_bound:g} s (from {gap_at:.1f} s)",
        ),
        Check(
            "recovers after faults",
            windows > 0 and not not_recovered,
            "; ".join(not_recovered[:3])
            or f"{windows} quiet windows, longest gap in them {quiet_gap:.2f} s "
            f"<= {QUIET_POLL_GAP_BOUND_S:g} s, failed polls cleared in each",
        ),
        Check(
            "final slew lands",
            took is not None and miss <= FINAL_LANDING_BOUND_DEG and not failures_after,
            f"{'stuck' if took is None else f'{took:.1f} s'}, {miss:.3f}° from its target "
            f"<= {FINAL_LANDING_BOUND_DEG:g}°; problems after it: {night.last_problems or 'none'}",
        ),
        Check(
            "tube within its meridian limit (device's sky)",
            samples > 0 and excess_deg <= DEVICE_MERIDIAN_TOLERANCE_DEG,
            f"worst {excess_deg:+.3f}° past the limit <= {DEVICE_MERIDIAN_TOLERANCE_DEG:g}° "
            f"({worst}; {samples} samples of the axes at rest or tracking); serve's meridian "
            f"stops (its clock): {len(night.meridian_stops)}",
        ),
        Check(
            "Stellarium stream steady",
            stream_gap <= STREAM_GAP_BOUND_S,
            f"longest gap between positions {stream_gap:.2f} s <= {STREAM_GAP_BOUND_S:g} s",
        ),
        Check(
            "memory flat",
            rss_growth_mib <= rss_bound_mib,
            f"RSS median first quarter {statistics.median(rss_first) / 1024:.1f} MiB, last "
            f"{statistics.median(rss_last) / 1024:.1f} MiB: {rss_growth_mib:+.2f} MiB "
            f"<= {rss_bound_mib:.2f}; trend {trend_mib_per_hour:+.2f} MiB per hour",
        ),
        Check(
            "fds flat, back to baseline",
            fd_growth <= FD_GROWTH_BOUND and not left_open,
            f"most fds first quarter {max(fds_first)}, last {max(fds_last)}; "
            f"{report.baseline_files.total()} before the clients, "
            f"{report.final_files.total()} after; left open: {_files_text(left_open)} "
            f"(data files opened once and kept: {_files_text(data_files)})",
        ),
        Check(
            "clean exits",
            report.exit_codes == (0, 0),
            f"serve {report.exit_codes[0]}, emulator {report.exit_codes[1]}",
        ),
    ]


def print_report(report: SoakReport) -> None:
    night, config = report.night, report.config
    print(
        f"soak: {config.hours:g} simulated hours at x{config.rate:g} = {config.real_s:.0f} s real, "
        f"seed {config.seed}"
    )
    print(f"serve before the clients: {_files_text(report.baseline_files)}")
    print(f"{'protocol':<12}{'requests':>10}{'errors':>8}{'slowest s':>11}{'late':>6}  slowest")
    for name, record in sorted(night.requests.items()):
        print(
            f"{name:<12}{record.count:>10}{record.errors:>8}"
            f"{record.slowest_s:>11.2f}{len(record.late):>6}  {record.slowest}"
        )
    print(
        f"wire commands (emulator) {night.wire_commands}, "
        f"{night.wire_commands / config.real_s:.1f}/s"
    )
    kinds = Counter(kind for _, kind in night.faults)
    print(
        f"faults fired {len(night.faults)}: "
        + ", ".join(f"{k} {n}" for k, n in sorted(kinds.items()))
    )
    print(f"slews {night.slews}; slew times " + _spread(night.slew_times))
    print(
        "fault switches "
        + ", ".join(f"{line} at {at:.0f} s" for at, line in night.fault_switches if line != "add")
    )
    print(
        "client connections " + ", ".join(f"{k} {n}" for k, n in sorted(night.reconnects.items()))
    )
    print(
        "answered errors "
        + (", ".join(f"{n}x {t}" for t, n in night.error_texts.most_common(6)) or "none")
    )
    after_motion = sum(
        any(0.0 <= stop - t <= 3.0 for t, _ in night.motion_commands) for stop in night.guard_stops
    )
    print(
        f"horizon guard stops {len(night.guard_stops)}, {after_motion} of them within 3 s of a "
        f"motion command; serve's meridian stops {len(night.meridian_stops)} (its clock, not the "
        "device's sky)"
    )
    print(f"serve's first dashboard page (cold, before the night): {night.first_page_s:.2f} s")
    print(
        f"serve log lines {len(night.serve_log)}"
        + "".join(f"\n  {line}" for line in night.serve_log[-5:])
    )
    tenths = [
        [
            rss
            for t, rss, _ in night.memory
            if k * config.real_s / 10 <= t < (k + 1) * config.real_s / 10
        ]
        for k in range(10)
    ]
    print(
        "serve RSS MiB by tenth of the night (median): "
        + " ".join(f"{statistics.median(tenth) / 1024:.1f}" for tenth in tenths if tenth)
    )
    for check in report.checks:
        print(f"check {check.name}: {'ok' if check.passed else 'FAIL'} - {check.detail}")
    print(f"soak {'PASSED' if report.passed else 'FAILED'}")


def _spread(values: list[float]) -> str:
    if not values:
        return "none"
    ordered = sorted(values)
    return (
        f"median {statistics.median(ordered):.2f} s, "
        f"p95 {ordered[int(0.95 * (len(ordered) - 1))]:.2f} s, max {ordered[-1]:.2f} s"
    )
