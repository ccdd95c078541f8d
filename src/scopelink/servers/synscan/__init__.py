"""The SynScan hand control server: INDI, Stellarium or SkySafari talk to it as to a real one.

- `config`: `SynScanConfig` (model, firmware, alignment, latency) and `Quirks` of real firmware;
- `device`: `SynScanHandControl`, each command as calls on a Mount and one reply;
- `server`: `SynScanServer`, the per-link loop (framing, order, latency, faults);
- `emulator`: `SynScanEmulator`, all of it on a pty, TCP port or memory pair.
"""

from scopelink.servers.synscan.config import DEFAULT_FIRMWARE, Quirks, SynScanConfig
from scopelink.servers.synscan.device import AxisPositioning, SynScanHandControl
from scopelink.servers.synscan.emulator import SynScanEmulator
from scopelink.servers.synscan.server import SynScanServer, command_key

__all__ = [
    "DEFAULT_FIRMWARE",
    "AxisPositioning",
    "Quirks",
    "SynScanConfig",
    "SynScanEmulator",
    "SynScanHandControl",
    "SynScanServer",
    "command_key",
]
