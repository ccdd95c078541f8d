"""The live web dashboard: sky chart, controls, status, health and decoded traffic in a browser.

``async with Dashboard(mount, port=8080) as dashboard: print(dashboard.url)``; see
``docs/dashboard.md``.
"""

from scopelink.web.dashboard import Dashboard
from scopelink.web.traffic import ProtocolChooser, protocol_by_port

__all__ = ["Dashboard", "ProtocolChooser", "protocol_by_port"]
