"""Astronomy core on ERFA: time scales, sidereal time, frames, refraction."""
