"""A deliberately misaligned sky: where the simulated tube really points.

The simulated mount is perfect in its own frame: its readings are what a perfectly set up mount
would read. A :class:`Misalignment` says how the real sky differs from that frame, the way a
hastily set up tripod does: the polar axis (an alt-az mount's base) tilted by ``polar_az_deg``
and ``polar_alt_deg``, and the zero points of the two axes off by ``zero_primary_deg`` and
``zero_secondary_deg``. The mount's readings, and the hand control's, stay in the mount's frame;
:meth:`Misalignment.true_of` gives the position the tube really points at, which only tests,
benches and a simulated camera may know (``SimulatedMount.true_pointing``).

Axes: on an equatorial mount the primary axis is the hour angle and the secondary the
declination, and the polar axis is turned about the zenith (azimuth error) and about the
east-west axis (altitude error). On an alt-az mount the primary axis is the azimuth and the
secondary the altitude, and the base is tilted about the east-west axis (``polar_alt_deg``) and
about the north-south axis (``polar_az_deg``). Written apart from ``scopelink.mount``'s pointing
model on purpose, so that the tests check one against the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["Misalignment", "parse_misalignment"]

_Matrix = NDArray[np.float64]


def _vec(alt_deg: float, az_deg: float) -> _Matrix:
    a, z = math.radians(alt_deg), math.radians(az_deg)
    return np.array([math.cos(a) * math.cos(z), math.cos(a) * math.sin(z), math.sin(a)])


def _angles(v: _Matrix) -> tuple[float, float]:
    x, y, z = (float(c) for c in v)
    return math.degrees(math.atan2(z, math.hypot(x, y))), math.degrees(math.atan2(y, x)) % 360.0


def _turn(axis: int, degrees: float) -> _Matrix:
    c, s = math.cos(math.radians(degrees)), math.sin(math.radians(degrees))
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


@dataclass(frozen=True, slots=True)
class Misalignment:
    """How the real sky differs from the simulated mount's frame (degrees, all 0: perfect)."""

    zero_primary_deg: float = 0.0
    zero_secondary_deg: float = 0.0
    polar_az_deg: float = 0.0
    polar_alt_deg: float = 0.0

    def true_of(
        self, alt_deg: float, az_deg: float, latitude_deg: float, *, equatorial: bool
    ) -> tuple[float, float]:
        """The true observed alt/az the tube points at when the mount reads this alt/az."""
        v = _vec(alt_deg, az_deg)
        if equatorial:
            phi = math.radians(latitude_deg)
            # (north, east, up) -> (meridian, east, pole): turn by the colatitude about east.
            to_eq = np.array(
                [
                    [-math.sin(phi), 0.0, math.cos(phi)],
                    [0.0, 1.0, 0.0],
                    [math.cos(phi), 0.0, math.sin(phi)],
                ]
            )
            e = to_eq @ v
            hour = math.atan2(-float(e[1]), float(e[0])) - math.radians(self.zero_primary_deg)
            dec = math.asin(max(-1.0, min(1.0, float(e[2])))) - math.radians(
                self.zero_secondary_deg
            )
            e = np.array(
                [math.cos(dec) * math.cos(hour), -math.cos(dec) * math.sin(hour), math.sin(dec)]
            )
            v = to_eq.T @ e
            tilt = _turn(2, self.polar_az_deg) @ _turn(1, -self.polar_alt_deg)
        else:
            alt, az = _angles(v)
            v = _vec(alt - self.zero_secondary_deg, az - self.zero_primary_deg)
            tilt = _turn(1, -self.polar_alt_deg) @ _turn(0, self.polar_az_deg)
        return _angles(tilt.T @ v)

    def reading_of(
        self, alt_deg: float, az_deg: float, latitude_deg: float, *, equatorial: bool
    ) -> tuple[float, float]:
        """Where the mount reads when the tube truly points at this alt/az (solved by
        iterating :meth:`true_of`, which is all a simulated observer needs)."""
        guess = _vec(alt_deg, az_deg)
        goal = guess
        for _ in range(50):
            seen = _vec(*self.true_of(*_angles(guess), latitude_deg, equatorial=equatorial))
            error = goal - seen
            guess = guess + error
            guess = guess / np.linalg.norm(guess)
            if float(np.linalg.norm(error)) < 1.0e-12:
                break
        return _angles(guess)


def parse_misalignment(text: str) -> Misalignment:
    """``"ZP1,ZP2,POLAR_AZ,POLAR_ALT"`` (degrees) as given to ``scopelink emulate``; a clear
    ``ValueError`` otherwise (each at most 10° in size)."""
    parts = text.split(",")
    try:
        values = [float(part) for part in parts]
    except ValueError:
        values = []
    if len(values) != 4 or not all(math.isfinite(v) and abs(v) <= 10.0 for v in values):
        raise ValueError(
            f"misalignment {text!r} must be four numbers of degrees within ±10, "
            "ZERO_PRIMARY,ZERO_SECONDARY,POLAR_AZ,POLAR_ALT (e.g. 1.5,-2,3,-1)"
        )
    return Misalignment(*values)
