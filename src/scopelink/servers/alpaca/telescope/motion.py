"""Guiding and axis motion: PulseGuide, MoveAxis and the axes' CanMoveAxis and AxisRates."""

from __future__ import annotations

from scopelink.mount import MAX_PULSE_GUIDE_MS, GuideDirection, MountAxis
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup

__all__ = ["MotionMembers"]

_GUIDE_DIRECTIONS = (
    GuideDirection.NORTH,
    GuideDirection.SOUTH,
    GuideDirection.EAST,
    GuideDirection.WEST,
)
"""ASCOM ``GuideDirections`` 0..3, in order."""


def _axis(params: Params) -> int:
    """ASCOM ``TelescopeAxes``: 0 primary, 1 secondary, 2 tertiary (no mount here has one)."""
    return params.integer("Axis", 0, 2)


class MotionMembers(MemberGroup):
    """Manual motion: guide pulses and moving an axis at a rate."""

    def members(self) -> dict[str, Member]:
        return {
            "canmoveaxis": Member(get=self._can_move_axis, needs_connection=False),
            "axisrates": Member(get=self._axis_rates, needs_connection=False),
            "moveaxis": Member(put=self._move_axis),
            "pulseguide": Member(put=self._pulse_guide),
        }

    def _axis_rates(self, params: Params) -> list[dict[str, float]]:
        axis = _axis(params)
        caps = self.session.mount.capabilities
        if axis == 2 or not caps.can_move_axis[axis]:
            return []
        return [{"Minimum": 0.0, "Maximum": caps.max_axis_rate_deg_s}]

    def _can_move_axis(self, params: Params) -> bool:
        axis = _axis(params)
        return axis != 2 and self.session.mount.capabilities.can_move_axis[axis]

    async def _move_axis(self, params: Params) -> None:
        axis = _axis(params)
        rate = params.number("Rate")
        mount = self.session.mount
        if axis == 2 or not mount.capabilities.can_move_axis[axis]:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, f"axis {axis} cannot be moved at a rate")
        self.session.require_unparked()
        await self.session.call(mount.move_axis(MountAxis(axis), rate))

    async def _pulse_guide(self, params: Params) -> None:
        direction = params.integer("Direction", 0, 3)
        duration = params.integer("Duration", 0, MAX_PULSE_GUIDE_MS)
        mount = self.session.mount
        if not mount.capabilities.can_pulse_guide:
            raise AlpacaError(ErrorNumber.NOT_IMPLEMENTED, "this mount cannot pulse-guide")
        self.session.require_unparked()
        await self.session.call(mount.pulse_guide(_GUIDE_DIRECTIONS[direction], duration))
