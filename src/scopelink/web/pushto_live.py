"""The push-to target the dashboard follows live (``POST /api/pushto``): its figures, how far to
push the tube up/down and left/right, ride on every WebSocket update, so no page polls for them.

There is one target for every open page, as there is one telescope; a name is looked up again at
each update (the Moon and planets move), from the mount's last reading.
"""

from __future__ import annotations

from scopelink.astro.catalog import EphemerisRangeError, lookup
from scopelink.drivers.skytracker.pushto import push_to
from scopelink.mount import Mount, MountState, NotConnectedError

__all__ = ["PushToTarget"]


class PushToTarget:
    """The target (a catalogue name) and its figures from a state."""

    def __init__(self, mount: Mount) -> None:
        self._mount = mount
        self.name: str | None = None

    def set(self, name: str | None) -> None:
        """Follow ``name`` (checked: unknown names raise with suggestions), or nothing."""
        if name is not None:
            name = lookup(name, self._mount.now(), self._mount.site).name
        self.name = name

    def figures(self, state: MountState) -> dict[str, object] | None:
        """``PushTo.as_json()`` for the target, ``{"target", "error"}`` when it cannot be
        computed now, None without a target."""
        name = self.name
        if name is None:
            return None
        try:
            found = lookup(name, state.read_at, self._mount.site)
            figures = push_to(
                found.name,
                found.ra_hours % 24.0,
                found.dec_deg,
                state=state,
                when=state.read_at,
                site=self._mount.site,
            )
        except (NotConnectedError, EphemerisRangeError) as error:
            return {"target": name, "error": str(error)}
        return figures.as_json()
