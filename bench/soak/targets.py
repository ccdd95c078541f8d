"""Where the clients slew: random positions well above the horizon."""

from __future__ import annotations

import math
import random
from dataclasses import dataclass
from datetime import UTC, datetime

from bench.soak.config import LOWEST_TARGET_ALT_DEG, SITE
from scopelink.astro import observed_to_apparent, observed_to_j2000


@dataclass(frozen=True)
class Target:
    alt_deg: float
    az_deg: float
    ra_of_date_hours: float
    dec_of_date_deg: float
    ra_j2000_hours: float
    dec_j2000_deg: float


def random_target(chance: random.Random) -> Target:
    """A position well above the horizon now (real time: what the driver checks against)."""
    alt = chance.uniform(LOWEST_TARGET_ALT_DEG, 80.0)
    az = chance.uniform(0.0, 360.0)
    now = datetime.now(UTC)
    ra, dec = observed_to_apparent(alt, az, now, SITE)
    ra_j2000, dec_j2000 = observed_to_j2000(alt, az, now, SITE)
    return Target(alt, az, ra, dec, ra_j2000, dec_j2000)


def separation_deg(ra1_h: float, dec1: float, ra2_h: float, dec2: float) -> float:
    a1, d1, a2, d2 = map(math.radians, (ra1_h * 15, dec1, ra2_h * 15, dec2))
    cosine = math.sin(d1) * math.sin(d2) + math.cos(d1) * math.cos(d2) * math.cos(a1 - a2)
    return math.degrees(math.acos(max(-1.0, min(1.0, cosine))))
