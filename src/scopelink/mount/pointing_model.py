"""The pointing model: where the mount reads when the tube points at a true position, and back.

Pure arithmetic on observed (refracted) altitude and azimuth, with numpy; no state, no I/O. The
terms follow TPoint's names, each an exact geometric error rather than its first-order formula
(so a 5° polar error is fitted to arcseconds, not to the ~10′ a linear model leaves):

equatorial mounts (``EQUATORIAL_TERMS``)
    ``IH``, ``ID`` zero points of the hour-angle and declination axes; ``CH`` collimation (cone:
    ``CH·sec δ`` added to the hour angle, sec δ capped at |δ| = 85°); ``MA``, ``ME`` the polar
    axis displaced in azimuth (a rotation of the sky about the zenith) and in elevation (about
    the east-west axis).
alt-az mounts (``ALTAZ_TERMS``)
    ``IA``, ``IE`` zero points of the azimuth and elevation axes; ``CA`` collimation
    (``CA·sec E`` added to the azimuth, capped at E = 85°); ``AN``, ``AW`` the base tilted
    towards north (a rotation about the east-west axis) and towards west (about the north-south
    axis).

Sign convention: the model maps the *true* position to the mount's *reading*; each term is the
reading minus the truth it causes (positive ``IH``: the mount reads a larger hour angle).
:func:`fit` solves for the terms by Gauss-Newton least squares (``numpy.linalg.lstsq``) on the
3-D unit-vector differences of the syncs. Two syncs fit the two zero points and the two tilts (four
equations, four terms). One sync, or syncs too close together to tell the terms apart, fit a rigid
turn of the sky only (``ROTATION_TERMS``: the zero point of the primary axis and the two tilts,
minimum norm), which moves no position farther than the sync.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "ALTAZ_TERMS",
    "EQUATORIAL_TERMS",
    "FULL_MODEL_MIN_SYNCS",
    "ROTATION_TERMS",
    "FittedModel",
    "ModelFrame",
    "fit",
]

EQUATORIAL_TERMS = ("IH", "ID", "CH", "MA", "ME")
ALTAZ_TERMS = ("IA", "IE", "CA", "AN", "AW")
FULL_MODEL_MIN_SYNCS = 3
"""From this many syncs on, all five terms are fitted (fewer: see :func:`fit`)."""
_SEC_CAP_DEG = 85.0
_MAX_CONDITION = 1.0e4
"""A full fit whose normal matrix is worse conditioned than this (syncs bunched together, or on
one great circle) falls back to the zero points: its terms would be noise."""

Vector = npt.NDArray[np.float64]


@dataclass(frozen=True, slots=True)
class ModelFrame:
    """What the model is fitted for: the mount's kind and the site's latitude."""

    equatorial: bool
    latitude_deg: float

    @property
    def terms(self) -> tuple[str, ...]:
        return EQUATORIAL_TERMS if self.equatorial else ALTAZ_TERMS


def _unit(alt_deg: float, az_deg: float) -> Vector:
    alt, az = math.radians(alt_deg), math.radians(az_deg)
    return np.array([math.cos(alt) * math.cos(az), math.cos(alt) * math.sin(az), math.sin(alt)])


def _altaz(v: Vector) -> tuple[float, float]:
    x, y, z = (float(c) for c in v)
    alt = math.degrees(math.atan2(z, math.hypot(x, y)))
    return alt, math.degrees(math.atan2(y, x)) % 360.0


def _rot(axis: int, angle_rad: float) -> Vector:
    """Rotation of a vector by ``angle_rad`` about the frame's axis 0, 1 or 2."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    i, j = [k for k in range(3) if k != axis]
    m = np.eye(3)
    m[i, i], m[i, j], m[j, i], m[j, j] = c, -s, s, c
    return m


def _to_equator(latitude_deg: float) -> Vector:
    """Alt-az (north, east, up) -> equatorial (h=0, h=-6h, pole) unit vectors."""
    phi = math.radians(latitude_deg)
    s, c = math.sin(phi), math.cos(phi)
    return np.array([[-s, 0.0, c], [0.0, 1.0, 0.0], [c, 0.0, s]])


def _sec(angle_rad: float) -> float:
    cap = math.radians(_SEC_CAP_DEG)
    return 1.0 / math.cos(max(-cap, min(cap, angle_rad)))


@dataclass(frozen=True, slots=True)
class FittedModel:
    """Five terms (radians, in the frame's order; unfitted ones 0) and how they were found."""

    frame: ModelFrame
    terms_rad: tuple[float, ...]
    fitted: tuple[str, ...]

    def terms_arcmin(self) -> dict[str, float]:
        return {
            name: math.degrees(value) * 60.0
            for name, value in zip(self.frame.terms, self.terms_rad, strict=True)
        }

    def _tilt(self) -> Vector:
        _, _, _, a, b = self.terms_rad
        if self.frame.equatorial:  # MA about the zenith, ME about the east axis
            return _rot(2, a) @ _rot(1, -b)
        return _rot(1, -a) @ _rot(0, b)  # AN about the east axis, AW about the north axis

    def reading_of(self, alt_deg: float, az_deg: float) -> tuple[float, float]:
        """Where the mount reads when the tube points at this true alt/az."""
        return _altaz(self._reading_vector(_unit(alt_deg, az_deg)))

    def true_of(self, alt_deg: float, az_deg: float) -> tuple[float, float]:
        """Where the tube points when the mount reads this alt/az (the exact inverse)."""
        zero1, zero2, cone, _, _ = self.terms_rad
        v = _unit(alt_deg, az_deg)
        if self.frame.equatorial:
            to_eq = _to_equator(self.frame.latitude_deg)
            e = to_eq @ v
            h, d = math.atan2(-e[1], e[0]), math.asin(max(-1.0, min(1.0, float(e[2]))))
            d -= zero2
            h -= zero1 + cone * _sec(d)
            e = np.array([math.cos(d) * math.cos(h), -math.cos(d) * math.sin(h), math.sin(d)])
            v = to_eq.T @ e
        else:
            alt, az = _altaz(v)
            el = math.radians(alt) - zero2
            a = math.radians(az) - zero1 - cone * _sec(el)
            v = np.array([math.cos(el) * math.cos(a), math.cos(el) * math.sin(a), math.sin(el)])
        return _altaz(self._tilt().T @ v)

    def _reading_vector(self, true: Vector) -> Vector:
        zero1, zero2, cone, _, _ = self.terms_rad
        v = self._tilt() @ true
        if self.frame.equatorial:
            to_eq = _to_equator(self.frame.latitude_deg)
            e = to_eq @ v
            h, d = math.atan2(-e[1], e[0]), math.asin(max(-1.0, min(1.0, float(e[2]))))
            h += zero1 + cone * _sec(d)
            d += zero2
            e = np.array([math.cos(d) * math.cos(h), -math.cos(d) * math.sin(h), math.sin(d)])
            return np.asarray(to_eq.T @ e)
        el = math.atan2(float(v[2]), math.hypot(float(v[0]), float(v[1])))
        a = math.atan2(float(v[1]), float(v[0])) + zero1 + cone * _sec(el)
        el += zero2
        return np.array([math.cos(el) * math.cos(a), math.cos(el) * math.sin(a), math.sin(el)])

    def residual_arcmin(self, reading: tuple[float, float], true: tuple[float, float]) -> float:
        """How far (arcmin) the model's predicted reading for ``true`` is from ``reading``."""
        predicted = self._reading_vector(_unit(*true))
        cosine = float(np.clip(predicted @ _unit(*reading), -1.0, 1.0))
        return math.degrees(math.acos(cosine)) * 60.0


def fit(
    frame: ModelFrame, readings: list[tuple[float, float]], trues: list[tuple[float, float]]
) -> FittedModel:
    """The terms that best map each true alt/az to its reading (least squares)."""
    if not readings:
        return FittedModel(frame, (0.0,) * 5, ())
    model = None
    if len(readings) >= FULL_MODEL_MIN_SYNCS:
        model = _gauss_newton(frame, readings, trues, (0, 1, 2, 3, 4))
    elif len(readings) == 2:  # four equations: the turn and the secondary zero point
        model = _gauss_newton(frame, readings, trues, (0, 1, 3, 4))
    if model is None:
        # The smallest turn (axis-angle, minimum norm), then the same turn in the model's terms,
        # fitted exactly on points spread over the sky.
        turn = _smallest_turn(readings, trues)
        spread = [(30.0, 0.0), (60.0, 90.0), (45.0, 180.0), (20.0, 270.0), (80.0, 45.0)]
        turned = [_altaz(turn @ _unit(*t)) for t in spread]
        model = _gauss_newton(frame, turned, spread, ROTATION_TERMS)
    assert model is not None  # a rotation is never refused
    return model


def _rodrigues(omega: Vector) -> Vector:
    angle = float(np.linalg.norm(omega))
    if angle < 1.0e-15:
        return np.eye(3)
    k = omega / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    turn = np.eye(3) + math.sin(angle) * cross + (1.0 - math.cos(angle)) * (cross @ cross)
    return np.asarray(turn, dtype=np.float64)


def _smallest_turn(readings: list[tuple[float, float]], trues: list[tuple[float, float]]) -> Vector:
    """The rotation of least angle that best carries each true position onto its reading."""
    true_vectors = [_unit(*t) for t in trues]

    def predicted(omega: Vector) -> Vector:
        turn = _rodrigues(omega)
        return np.concatenate([turn @ t for t in true_vectors])

    omega = _least_squares(predicted, np.concatenate([_unit(*r) for r in readings]), 3, None)
    assert omega is not None  # no condition limit asked
    return _rodrigues(omega)


def _least_squares(
    predicted: Callable[[Vector], Vector],
    measured: Vector,
    count: int,
    max_condition: float | None,
) -> Vector | None:
    """Gauss-Newton from zero: the ``count`` parameters whose ``predicted`` best matches
    ``measured`` (minimum-norm steps; numerical derivatives). None if the normal matrix is worse
    conditioned than ``max_condition``."""
    p = np.zeros(count)
    step = 1.0e-7
    for _ in range(12):
        base = predicted(p)
        jacobian = np.column_stack(
            [(predicted(p + step * np.eye(count)[k]) - base) / step for k in range(count)]
        )
        if max_condition is not None and np.linalg.cond(jacobian.T @ jacobian) > max_condition:
            return None
        delta, *_ = np.linalg.lstsq(jacobian, measured - base, rcond=1.0e-6)
        p = p + delta
        if float(np.max(np.abs(delta))) < 1.0e-12:
            break
    return p


ROTATION_TERMS = (0, 3, 4)
"""The terms of a rigid turn of the sky: about the pole (or zenith), and two tilts. With fewer
than three syncs they hold the smallest turn that carries each star onto its reading (least
squares on the turn's axis-angle vector, minimum norm): with one sync no position moves farther
than the sync did."""


def _gauss_newton(
    frame: ModelFrame,
    readings: list[tuple[float, float]],
    trues: list[tuple[float, float]],
    indices: tuple[int, ...],
) -> FittedModel | None:
    true_vectors = [_unit(*t) for t in trues]
    names = tuple(frame.terms[i] for i in indices)
    count = len(indices)

    def model_of(p: Vector) -> FittedModel:
        terms = [0.0] * 5
        for i, value in zip(indices, p, strict=True):
            terms[i] = float(value)
        return FittedModel(frame, tuple(terms), names)

    def predicted(p: Vector) -> Vector:
        m = model_of(p)
        return np.concatenate([m._reading_vector(t) for t in true_vectors])

    measured = np.concatenate([_unit(*r) for r in readings])
    p = _least_squares(predicted, measured, count, _MAX_CONDITION if count > 3 else None)
    return None if p is None else model_of(p)
