"""Stellarium's telescope-control server (binary protocol on TCP 10001) over any Mount."""

from scopelink.servers.stellarium.server import DEFAULT_PORT, Equinox, StellariumServer

__all__ = ["DEFAULT_PORT", "Equinox", "StellariumServer"]
