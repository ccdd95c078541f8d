"""Protocol clients: drivers that implement the Mount API over a link to a real device.

- `synscan`: `SynScanMount`, a Sky-Watcher SynScan hand control;
- `skytracker`: `SkyTrackerMount`, a Sky Tracker motor box (and its Sky Commander);
- `common`: what both drivers share (link factory, statistics, reconnection, position maths);
- `open`: a device by its string (``synscan:/dev/ttyUSB0``, ``sim:eq6``, a bare port to
  autodetect): :func:`open_mount`, :func:`create_mount`, :func:`parse_device`.

Both drivers have one shape: ``Driver(link, site=..., timeout_s=...)`` constructs without
touching the link; ``await driver.connect()`` (or ``await Driver.open(link, ...)``, which
constructs and connects) opens it. See the "Drivers" section of ``docs/architecture.md``.
"""

from scopelink.drivers.open import (
    DeviceOpenError,
    DeviceSpec,
    create_mount,
    open_mount,
    parse_device,
)

__all__ = ["DeviceOpenError", "DeviceSpec", "create_mount", "open_mount", "parse_device"]
