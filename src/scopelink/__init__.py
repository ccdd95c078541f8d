"""scopelink: PC control, emulation and bridging of SynScan and Sky Tracker telescope mounts."""

__version__ = "0.1.0"
