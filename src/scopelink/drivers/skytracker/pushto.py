"""Push-to figures: how far, and which way, to push the scope on each axis to reach a target.

Computed on the PC from the position the mount last reported (the Sky Commander's J2000
reading turned into observed alt/az) and the target's observed alt/az at the same time, so the
CLI (``scopelink skycommander pushto``) and the dashboard show the same figures for any mount.
They agree with the Sky Commander's own ``O`` offsets to its 3-decimal rounding.
"""

from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime

from scopelink.astro import Site, angular_separation_deg, j2000_to_observed, wrap_signed_degrees
from scopelink.mount import MountState, NotConnectedError

__all__ = ["ON_TARGET_DEG", "PushTo", "push_to"]

ON_TARGET_DEG = 0.05
"""Within this on both axes the line says "on target" (the reading's resolution is 0.001 h /
0.001°, and a hand can rarely place a scope better)."""


@dataclass(frozen=True, slots=True)
class PushTo:
    """Where the target is from where the scope points, on each axis (degrees)."""

    target: str
    up_deg: float
    """Altitude to go: positive up, negative down."""
    right_deg: float
    """Azimuth to go, the short way: positive right (compass azimuth increasing, clockwise seen
    from above), negative left."""
    distance_deg: float
    """Great-circle distance."""
    target_alt_deg: float
    target_az_deg: float

    @property
    def on_target(self) -> bool:
        return abs(self.up_deg) <= ON_TARGET_DEG and abs(self.right_deg) <= ON_TARGET_DEG

    def describe(self) -> str:
        """One line: ``M 31: altitude up 3.21°, azimuth left 12.40° (12.9° away)``."""
        if self.on_target:
            text = f"{self.target}: on target ({self.distance_deg:.2f}° away)"
        else:
            vertical = "up" if self.up_deg >= 0 else "down"
            sideways = "right" if self.right_deg >= 0 else "left"
            text = (
                f"{self.target}: altitude {vertical} {abs(self.up_deg):.2f}°, azimuth "
                f"{sideways} {abs(self.right_deg):.2f}° ({self.distance_deg:.2f}° away)"
            )
        if self.target_alt_deg < 0.0:
            text += ", below the horizon"
        return text

    def as_json(self) -> dict[str, object]:
        return {
            "target": self.target,
            "up_deg": self.up_deg,
            "right_deg": self.right_deg,
            "distance_deg": self.distance_deg,
            "target_alt_deg": self.target_alt_deg,
            "target_az_deg": self.target_az_deg,
            "on_target": self.on_target,
            "text": self.describe(),
        }


def push_to(
    target: str,
    ra_j2000_hours: float,
    dec_j2000_deg: float,
    *,
    state: MountState,
    when: datetime,
    site: Site,
) -> PushTo:
    """The figures from ``state``'s alt/az to the target's at ``when`` (the reading's time)."""
    if state.alt_deg is None or state.az_deg is None:
        raise NotConnectedError("the mount has reported no position yet")
    alt, az = j2000_to_observed(ra_j2000_hours, dec_j2000_deg, when, site)
    return PushTo(
        target,
        up_deg=alt - state.alt_deg,
        right_deg=wrap_signed_degrees(az - state.az_deg),
        distance_deg=angular_separation_deg(state.az_deg, state.alt_deg, az, alt),
        target_alt_deg=alt,
        target_az_deg=az,
    )
