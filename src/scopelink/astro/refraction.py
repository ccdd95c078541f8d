"""Atmospheric refraction: observed (refracted) <-> true (unrefracted) altitude.

The refraction R(h) is a function of the *observed* altitude h:

- above 6°, ERFA's model R = A tan z + B tan³ z with z = 90° - h and (A, B) from
  ``erfa.refco`` for the site's pressure, temperature, humidity and wavelength;
- below 5°, Bennett's formula R = cot(h + 7.31 / (h + 4.4)) arcmin, scaled by
  (P / 1010 hPa) (283 K / T), which stays finite and smooth to the horizon; it is evaluated at
  max(h, -1°), so R is constant (finite) below -1°;
- between 5° and 6° a smoothstep blend of the two, so R is continuous, smooth and decreasing.

Unrefracting is explicit (true = observed - R(observed)); refracting solves
observed - R(observed) = true by fixed-point iteration to 1e-12 degrees, so the two are exact
inverses of each other.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import overload

import erfa
import numpy as np
import numpy.typing as npt

from scopelink.astro._arrays import FloatArray, FloatOrArray, as_float_array, scalar_or_array
from scopelink.astro.site import Site

__all__ = [
    "BLEND_HIGH_DEG",
    "BLEND_LOW_DEG",
    "LOWEST_MODELLED_DEG",
    "RefractionModel",
    "observed_altitude_deg",
    "refraction_deg",
    "true_altitude_deg",
]

BLEND_LOW_DEG = 5.0
"""Below this observed altitude only the horizon formula (Bennett) is used."""
BLEND_HIGH_DEG = 6.0
"""Above this observed altitude only ERFA's A tan z + B tan³ z model is used."""
LOWEST_MODELLED_DEG = -1.0
"""Below this observed altitude the refraction is held at its value here."""

_CONVERGED_DEG = 1e-12
_SLOPE_STEP_DEG = 1e-6
_MAX_ITERATIONS = 100


@dataclass(frozen=True, slots=True)
class RefractionModel:
    """Refraction constants for one set of air conditions.

    ``a_rad`` and ``b_rad`` are ERFA's A and B; ``horizon_scale`` multiplies Bennett's formula.
    All three are zero when refraction is off.
    """

    a_rad: float
    b_rad: float
    horizon_scale: float

    @classmethod
    def for_site(cls, site: Site) -> RefractionModel:
        """The refraction constants for ``site``'s air (zero if its pressure is 0)."""
        return _model_for_site(site)

    @classmethod
    def compute(cls, site: Site) -> RefractionModel:
        """:meth:`for_site` without the cache."""
        pressure = site.effective_pressure_hpa
        if pressure <= 0.0:
            return cls(0.0, 0.0, 0.0)
        a_rad, b_rad = erfa.refco(
            pressure, site.temperature_c, site.relative_humidity, site.wavelength_um
        )
        horizon_scale = (pressure / 1010.0) * (283.0 / (273.0 + site.temperature_c))
        return cls(float(a_rad), float(b_rad), horizon_scale)

    def amount_scalar_deg(self, altitude: float) -> float:
        """:meth:`amount_deg` for one altitude, with ``math`` (a poll's single position costs
        a tenth of the array path's overhead); the same formula, term for term."""
        # Outside the blend one term has weight 0: skipping it gives the same double (both
        # terms are finite, so 1 * a + 0 * b == a).
        if altitude >= BLEND_HIGH_DEG:
            return self._erfa_deg(altitude)
        if altitude <= BLEND_LOW_DEG:
            return self._horizon_deg(altitude)
        x = min(max((altitude - BLEND_LOW_DEG) / (BLEND_HIGH_DEG - BLEND_LOW_DEG), 0.0), 1.0)
        weight = x * x * (3.0 - 2.0 * x)
        return weight * self._erfa_deg(altitude) + (1.0 - weight) * self._horizon_deg(altitude)

    def _erfa_deg(self, altitude: float) -> float:
        erfa_altitude = math.radians(min(max(altitude, BLEND_LOW_DEG), 90.0))
        tan_z = math.cos(erfa_altitude) / math.sin(erfa_altitude)
        return math.degrees((self.a_rad + self.b_rad * tan_z * tan_z) * tan_z)

    def _horizon_deg(self, altitude: float) -> float:
        horizon_altitude = min(max(altitude, LOWEST_MODELLED_DEG), BLEND_HIGH_DEG)
        bennett_arcmin = 1.0 / math.tan(
            math.radians(horizon_altitude + 7.31 / (horizon_altitude + 4.4))
        )
        return self.horizon_scale * bennett_arcmin / 60.0

    def amount_deg(self, observed_alt_deg: npt.ArrayLike) -> FloatArray:
        """Refraction in degrees (observed minus true altitude) at an observed altitude."""
        if isinstance(observed_alt_deg, float | int) or np.ndim(observed_alt_deg) == 0:
            return np.asarray(self.amount_scalar_deg(float(observed_alt_deg)))  # type: ignore[arg-type]
        altitude = as_float_array(observed_alt_deg)
        weight = _smoothstep((altitude - BLEND_LOW_DEG) / (BLEND_HIGH_DEG - BLEND_LOW_DEG))
        # Each formula is evaluated only inside its own range; the clamps avoid tan z -> inf.
        erfa_altitude = np.radians(np.clip(altitude, BLEND_LOW_DEG, 90.0))
        tan_z = np.cos(erfa_altitude) / np.sin(erfa_altitude)
        erfa_rad = (self.a_rad + self.b_rad * tan_z * tan_z) * tan_z
        horizon_altitude = np.clip(altitude, LOWEST_MODELLED_DEG, BLEND_HIGH_DEG)
        bennett_arcmin = 1.0 / np.tan(
            np.radians(horizon_altitude + 7.31 / (horizon_altitude + 4.4))
        )
        horizon_deg = self.horizon_scale * bennett_arcmin / 60.0
        amount: FloatArray = weight * np.degrees(erfa_rad) + (1.0 - weight) * horizon_deg
        return amount

    def unrefract(self, observed_alt_deg: npt.ArrayLike) -> FloatArray:
        """True (geometric) altitude for an observed altitude."""
        observed = as_float_array(observed_alt_deg)
        true: FloatArray = observed - self.amount_deg(observed)
        return true

    def refract(self, true_alt_deg: npt.ArrayLike) -> FloatArray:
        """Observed altitude for a true altitude: the exact inverse of :meth:`unrefract`."""
        if isinstance(true_alt_deg, float | int) or np.ndim(true_alt_deg) == 0:
            return np.asarray(self.refract_scalar_deg(float(true_alt_deg)))  # type: ignore[arg-type]
        true = as_float_array(true_alt_deg)
        observed = true + self.amount_deg(true)
        # Below LOWEST_MODELLED_DEG the refraction is constant, so there true + R is exact.
        flat = observed.reshape(-1)
        goal = true.reshape(-1)
        floor = self.amount_scalar_deg(LOWEST_MODELLED_DEG)
        todo = np.flatnonzero(goal + floor >= LOWEST_MODELLED_DEG)
        # Newton on g(h) = h - R(h) - true with R' in closed form: R is smooth and |R'| < 0.5,
        # so it converges in a few steps where the plain fixed point h = true + R(h) needs ~20
        # near the horizon. Each step works only on the elements still moving by more than
        # 1e-12 degrees.
        for _ in range(_MAX_ITERATIONS):
            if todo.size == 0:
                break
            guess = flat[todo]
            refraction, slope = self._amount_and_slope(guess)
            step = (guess - refraction - goal[todo]) / (1.0 - slope)
            flat[todo] = guess - step
            todo = todo[np.abs(step) > _CONVERGED_DEG]
        return observed

    def _amount_and_slope(self, altitude: FloatArray) -> tuple[FloatArray, FloatArray]:
        """:meth:`amount_deg` (the same expressions) and its derivative dR/dh, for Newton."""
        x = np.minimum(
            np.maximum((altitude - BLEND_LOW_DEG) / (BLEND_HIGH_DEG - BLEND_LOW_DEG), 0.0), 1.0
        )
        weight = x * x * (3.0 - 2.0 * x)
        weight_slope = 6.0 * x * (1.0 - x) / (BLEND_HIGH_DEG - BLEND_LOW_DEG)
        erfa_altitude = np.radians(np.minimum(np.maximum(altitude, BLEND_LOW_DEG), 90.0))
        tan_z = np.cos(erfa_altitude) / np.sin(erfa_altitude)
        tan_z2 = tan_z * tan_z
        erfa_rad = (self.a_rad + self.b_rad * tan_z2) * tan_z
        # d/dh of the degrees of f(tan z), tan z = cot h: -(A + 3B tan^2 z)(1 + tan^2 z).
        inside_erfa = (altitude > BLEND_LOW_DEG) & (altitude < 90.0)
        erfa_slope = -(self.a_rad + 3.0 * self.b_rad * tan_z2) * (1.0 + tan_z2) * inside_erfa
        horizon_altitude = np.minimum(np.maximum(altitude, LOWEST_MODELLED_DEG), BLEND_HIGH_DEG)
        offset = horizon_altitude + 4.4
        cot = 1.0 / np.tan(np.radians(horizon_altitude + 7.31 / offset))
        horizon_deg = self.horizon_scale * cot / 60.0
        inside_horizon = (altitude > LOWEST_MODELLED_DEG) & (altitude < BLEND_HIGH_DEG)
        horizon_slope = (
            -self.horizon_scale
            / 60.0
            * (1.0 + cot * cot)
            * np.radians(1.0 - 7.31 / (offset * offset))
        ) * inside_horizon
        erfa_deg = np.degrees(erfa_rad)
        amount = weight * erfa_deg + (1.0 - weight) * horizon_deg
        slope = (
            weight_slope * (erfa_deg - horizon_deg)
            + weight * erfa_slope
            + (1.0 - weight) * horizon_slope
        )
        return amount, slope

    def refract_scalar_deg(self, true: float) -> float:
        """:meth:`refract` for one altitude, in floats (the plain fixed point ``observed = true +
        R(observed)`` to 1e-12 degrees); ``true`` itself when refraction is off."""
        if not self.horizon_scale and not self.a_rad and not self.b_rad:
            return true
        observed = true + self.amount_scalar_deg(true)
        for _ in range(_MAX_ITERATIONS):
            updated = true + self.amount_scalar_deg(observed)
            step = abs(updated - observed)
            observed = updated
            if step <= _CONVERGED_DEG:
                break
        return observed


@functools.lru_cache(maxsize=64)
def _model_for_site(site: Site) -> RefractionModel:
    return RefractionModel.compute(site)


def _smoothstep(x: FloatArray) -> FloatArray:
    clipped = np.clip(x, 0.0, 1.0)
    smooth: FloatArray = clipped * clipped * (3.0 - 2.0 * clipped)
    return smooth


@overload
def refraction_deg(observed_alt_deg: float, site: Site) -> float: ...
@overload
def refraction_deg(observed_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray: ...
def refraction_deg(observed_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray:
    """Refraction in degrees at an observed altitude for ``site``'s air (0 if pressure is 0)."""
    return scalar_or_array(RefractionModel.for_site(site).amount_deg(observed_alt_deg))


@overload
def observed_altitude_deg(true_alt_deg: float, site: Site) -> float: ...
@overload
def observed_altitude_deg(true_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray: ...
def observed_altitude_deg(true_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray:
    """Observed (refracted) altitude in degrees for a true altitude."""
    return scalar_or_array(RefractionModel.for_site(site).refract(true_alt_deg))


@overload
def true_altitude_deg(observed_alt_deg: float, site: Site) -> float: ...
@overload
def true_altitude_deg(observed_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray: ...
def true_altitude_deg(observed_alt_deg: npt.ArrayLike, site: Site) -> FloatOrArray:
    """True (unrefracted) altitude in degrees for an observed altitude."""
    return scalar_or_array(RefractionModel.for_site(site).unrefract(observed_alt_deg))
