"""The meridian limit judged in the emulated device's own sky.

The emulator's sky runs ``rate`` times faster than real time (x100: 10 h in 6 min), while
``scopelink serve`` drives the SynScan device on the PC's real clock, as it drives a real hand
control. Serve's meridian watch takes the hour angle as its own sidereal time minus the RA the
hand control reports; with the device's sky ahead by ``(rate - 1)`` times the real time since the
start (9 h near the end of the night), that hour angle is not the tube's, and serve's
"tracking was stopped N° past the meridian" notices are about a sky the tube is not in
(``docs/reliability-soak.md``, "Meridian limits in the soak"). What the safety rule is about, the
counterweight, is judged here instead: from the emulated mount's physical axes, in its own sky,
against the limits its hand control keeps (the default ``limits.meridian_*_deg``).
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass

from scopelink.mount.meridian import SIDE_NAMES, limit_of
from scopelink.sim import SimulatedMount

SAMPLE_S = 0.05
"""How often (real seconds) the axes are sampled: 5 s of the device's sky at x100, 0.02° of
tracking."""


@dataclass
class DeviceMeridian:
    """The worst standing against the meridian limit the emulated tube reached while at rest or
    tracking (a goto's path is the physics' to plan, and lands within the limits)."""

    samples: int = 0
    worst_excess_deg: float = float("-inf")
    """Largest (degrees past the meridian) minus (the limit of that pier side)."""
    worst: str = "none"

    def line(self) -> str:
        return f"meridian {self.samples} {self.worst_excess_deg:.4f} {self.worst}"


def sample(mount: SimulatedMount, record: DeviceMeridian) -> None:
    """One look at the physical axes (after syncs, the tube's true hour angle)."""
    t = mount.elapsed()
    if mount.goto_in_progress:
        return
    counters = mount.counters_at(t)
    primary, secondary = (
        c - a.counter_offset_deg for c, a in zip(counters, mount.axes, strict=True)
    )
    side = mount.geometry.pier_side(primary, secondary)
    # The physics' own measure: (the limit of that side) minus (degrees past the meridian)
    margin = mount.geometry.meridian_margin_deg(primary, secondary, mount.limits)
    record.samples += 1
    if -margin > record.worst_excess_deg:
        limit = limit_of(mount.limits, side)
        record.worst_excess_deg = -margin
        record.worst = (
            f"{limit - margin:.2f}° past the meridian on the {SIDE_NAMES[side]} side (limit "
            f"{limit:g}°) at {t / 3600:.2f} h of the device's sky"
        )


async def watch(mount: SimulatedMount, record: DeviceMeridian) -> None:
    """Sample until cancelled."""
    while True:
        sample(mount, record)
        await asyncio.sleep(SAMPLE_S)


def parse(line: str) -> tuple[int, float, str]:
    """(samples, worst excess in degrees, where) from :meth:`DeviceMeridian.line`."""
    _, samples, excess, worst = line.rstrip("\n").split(" ", 3)
    return int(samples), float(excess), worst
