"""The SynScan driver: the Mount API over a Sky-Watcher SynScan hand control (protocol v3.3).

- `mount`: `SynScanMount`, the Mount implementation (identify, poll, goto, sync, rates, guiding);
- `exchange`: `SynScanWire`, one exchange at a time with timeouts, resynchronisation and reconnects;
- `identify`: what the model and firmware mean for capabilities;
- `settling`: goto completion from the position, for firmware whose ``L`` sticks.

See ``docs/drivers-synscan.md``.
"""

from scopelink.drivers.synscan.exchange import DEFAULT_TIMEOUT_S, SynScanWire
from scopelink.drivers.synscan.identify import HandControlInfo
from scopelink.drivers.synscan.mount import DEFAULT_GUIDE_RATE_DEG_S, NotAlignedError, SynScanMount

__all__ = [
    "DEFAULT_GUIDE_RATE_DEG_S",
    "DEFAULT_TIMEOUT_S",
    "HandControlInfo",
    "NotAlignedError",
    "SynScanMount",
    "SynScanWire",
]
