"""The SynScan driver: the Mount API over a Sky-Watcher SynScan hand control (protocol v3.3).

One class per concern, each building on the one before:

- `base`: `SynScanBase`, construction, identity, every exchange (owed stops first);
- `connection`: `SynScanConnection`, identify the hand control, reconnect a lost link;
- `polling`: `SynScanPolling`, read the state (``L``, ``e``, ``t``, ``p``, ``J``);
- `parking`: `SynScanParking`, park records, resume after a power cycle, slow gotos;
- `rates`: `SynScanRates`, custom tracking rates by a PC loop of rate slews (updates in place);
- `loop_target`: `LoopTarget`, the loop's integrated target (re-anchored by an update);
- `loop_pulses`: `SynScanLoopPulses`, guide pulses that join the loop, guide rates;
- `altaz_rates`: `SynScanAltAzRates`, the loop on an alt-az mount's axes;
- `mount`: `SynScanMount`, the commands (connect, gotos, syncs, abort, rates, guiding, park,
  site, time).

Beside them: `exchange` (`SynScanWire`, one exchange at a time with timeouts,
resynchronisation and reconnects), `identify` (what the model and firmware mean for
capabilities), `settling` (goto completion from the position, for firmware whose ``L`` sticks),
`stops` (stops owed after a failed exchange).

See ``docs/drivers-synscan.md``.
"""

from scopelink.drivers.synscan.base import DEFAULT_GUIDE_RATE_DEG_S
from scopelink.drivers.synscan.exchange import DEFAULT_TIMEOUT_S, SynScanWire
from scopelink.drivers.synscan.identify import HandControlInfo
from scopelink.drivers.synscan.mount import NotAlignedError, SynScanMount

__all__ = [
    "DEFAULT_GUIDE_RATE_DEG_S",
    "DEFAULT_TIMEOUT_S",
    "HandControlInfo",
    "NotAlignedError",
    "SynScanMount",
    "SynScanWire",
]
