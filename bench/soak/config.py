"""The night's configuration (length, speed-up, clients, faults) and the bounds every check uses."""

from __future__ import annotations

from dataclasses import dataclass

from scopelink.astro import Site

SITE = Site(51.4779, -0.0015)  # serve's and the emulator's default site (Greenwich)
LOWEST_TARGET_ALT_DEG = 25.0
"""Targets are drawn above this altitude: far above the 0 degree horizon even after the emulated
sky (x100) has turned under a tracking-off mount for a few real seconds."""

# --- the bounds every check uses (real seconds) --------------------------------------------------
DRIVER_TIMEOUT_S = 5.0
"""The SynScan driver's reply timeout (the spec's 5 s)."""
READ_BOUND_S = 2.0
"""A read answered from the state cache (Alpaca GETs, LX200 :GR#, SynScan e) never waits on the
wire, so even under faults it must come back within this."""
COMMAND_BOUND_S = 4 * DRIVER_TIMEOUT_S
"""A command that goes to the wire may meet a fault: a timeout, the resynchronising echo (which
may time out too) and one retry: 3 timeouts, plus scheduling: 20 s."""
SLEW_BOUND_S = 30.0
"""From the last motion command to Slewing false. A slew itself lasts under 1 real second at
x100; the rest is for a poll that meets faults (each up to 3 driver timeouts)."""
POLL_GAP_BOUND_S = 4 * DRIVER_TIMEOUT_S
"""Longest time the state cache may go without a new reading while faults fire (plus the
length of an outage when the night has them: the device is silent that long, then the exchange
in flight and its resynchronising echo time out)."""
QUIET_POLL_GAP_BOUND_S = DRIVER_TIMEOUT_S
"""Longest time without a new reading while no fault is in force (after ``QUIET_SETTLE_S``): a
longer gap means an exchange timed out with nothing to blame. Polls come every ~0.1 s; on a
loaded 2-core machine the longest quiet gap measured was 3.6 s (typically 1-1.5 s)."""
QUIET_SETTLE_S = 8.0
"""After a fault, time allowed before the quiet bounds apply: the worst single fault (a reply 6 s
late) costs 6 s, then the resynchronising echo and the retry."""
QUIET_WINDOW_MIN_S = 3.0
"""Shortest stretch without faults (after the settling time) that is judged."""
POSITION_READS = frozenset({"position", ":GR#", ":GD#", ":GA#", ":GZ#", "e"})
"""Reads of the position (Stellarium's stream, LX200, SynScan): not answered while the mount's
reading is older than ``stale_after_s`` (issue #11: no reply, no packet), which a fault that
silences the device causes. Unanswered inside a fault's span (to ``QUIET_SETTLE_S`` after it)
they are counted as withheld; anywhere else they fail the check like any unanswered read."""
STREAM_GAP_BOUND_S = 2.0
"""Stellarium positions come every 0.5 s whatever the wire does."""
RSS_GROWTH_FLOOR_MIB = 1.0
RSS_GROWTH_MIB_PER_HOUR = 2.0
"""Median RSS of the last quarter of the night (after a 10 % warm-up) minus that of the first
quarter may be at most the larger of 1 MiB (allocator noise) and 2 MiB per real hour between
them. The leak the soak found (~13 MiB/h under this load) failed it in a 30-hour night."""
FD_GROWTH_BOUND = 2
"""Most fds of the last quarter minus most of the first quarter (clients reconnect meanwhile)."""
DEVICE_MERIDIAN_TOLERANCE_DEG = 0.001
"""The emulated tube, at rest or tracking, may stand this far past its meridian limit in its own
sky: rounding only (its physics stops tracking and manual motion exactly at the limit)."""
FINAL_LANDING_BOUND_DEG = 1.0
"""After the faults, a last slew lands within this of its target (the state recovered)."""


@dataclass(frozen=True)
class SoakConfig:
    """One night: its length, speed-up, seed, clients and faults."""

    hours: float = 10.0
    rate: float = 100.0
    seed: int = 1
    alpaca_pollers: int = 2
    dashboards: int = 2
    poll_hz: float = 4.0
    faults_per_kind: int = 6
    fault_kinds: tuple[str, ...] = (
        "drop",
        "short",
        "malformed",
        "slow",
        "delay=1",
        "delay=6",
        "close",
    )
    """How often each probabilistic fault rule fires at most."""
    fault_firings: int = 9
    """The expected firings of each rule while faults are on, were it not limited to
    ``faults_per_kind``: a little more, so that each is used up by the end of the fault phase."""
    wire_commands_per_s: float = 25.0
    """SynScan commands per second assumed for the fault probabilities (~50/s reach the device
    when all is well, far fewer while faults fire)."""
    faults: bool = True
    """False: the same night without faults (for comparison)."""
    faults_until: float = 0.7
    """The fraction of the night after which every fault is cleared (the rest shows recovery)."""
    outages: tuple[tuple[float, str], ...] = ((0.3, "stall"), (0.5, "halt"))
    """(fraction of the night, kind): the device stops answering (stall) or reading (halt)..."""
    outage_s: float = 8.0
    """... for this long, then resumes."""
    scripted: tuple[tuple[float, str], ...] = ()
    """(fraction of the night, fault spec): rules added at set times (``once`` rules fire on the
    next command)."""

    @property
    def real_s(self) -> float:
        return self.hours * 3600.0 / self.rate

    def fault_specs(self) -> list[str]:
        """One rule per fault kind, each firing at most ``faults_per_kind`` times, with the chance
        per wire command that gives ``fault_firings`` over the fault phase."""
        if not self.faults:
            return []
        phase_s = self.faults_until * self.real_s
        probability = min(0.5, self.fault_firings / (phase_s * self.wire_commands_per_s))
        return [
            f"any:{kind}:times={self.faults_per_kind}:p={probability:.5f}"
            for kind in self.fault_kinds
        ]


FULL = SoakConfig()
QUICK = SoakConfig(
    hours=1.0,
    rate=200.0,
    alpaca_pollers=1,
    dashboards=1,
    # One of each kind that costs the wire least, one after the other, early in the night (drop
    # and short cost a timeout each, as the 6 s delay does)
    fault_kinds=(),
    scripted=(
        (0.03, "any:close:once"),
        (0.06, "any:malformed:once"),
        (0.09, "any:slow:once"),
        (0.12, "any:delay=6:once"),
    ),
    faults_until=0.6,
    outages=(),
)
