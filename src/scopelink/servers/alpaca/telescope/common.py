"""The ASCOM members every device type has: Connected, DeviceState, Name, Action...

See ``docs/alpaca.md``, "Members", for what each answers.
"""

from __future__ import annotations

from scopelink import __version__ as scopelink_version
from scopelink.mount import TrackingMode
from scopelink.servers.alpaca.errors import AlpacaError, ErrorNumber
from scopelink.servers.alpaca.params import Params
from scopelink.servers.alpaca.telescope.member import Member, MemberGroup, fixed, not_implemented
from scopelink.servers.alpaca.telescope.site import format_utc

__all__ = ["INTERFACE_VERSION", "CommonMembers"]

INTERFACE_VERSION = 4
"""ITelescopeV4 (ASCOM Platform 7): Connect/Disconnect/Connecting and DeviceState."""


class CommonMembers(MemberGroup):
    """Connection, identity, DeviceState and the (unsupported) actions and raw commands."""

    def members(self) -> dict[str, Member]:
        session = self.session
        config = session.config
        ni = not_implemented
        return {
            "connected": Member(
                get=lambda _: session.connected, put=self._put_connected, needs_connection=False
            ),
            "connecting": Member(get=lambda _: session.connecting, needs_connection=False),
            "connect": Member(put=lambda _: session.start_connect(), needs_connection=False),
            "disconnect": Member(put=lambda _: session.disconnect(), needs_connection=False),
            "devicestate": Member(get=self._device_state),
            "description": fixed(config.description),
            "driverinfo": Member(get=self._driver_info, needs_connection=False),
            "driverversion": fixed(scopelink_version),
            "interfaceversion": fixed(INTERFACE_VERSION),
            "name": fixed(config.name),
            "supportedactions": fixed([]),
            "action": Member(put=self._action, needs_connection=False),
            "commandblind": Member(put=ni("CommandBlind"), needs_connection=False),
            "commandbool": Member(put=ni("CommandBool"), needs_connection=False),
            "commandstring": Member(put=ni("CommandString"), needs_connection=False),
        }

    async def _put_connected(self, params: Params) -> None:
        if params.boolean("Connected"):
            await self.session.connect()
        else:
            self.session.disconnect()

    def _driver_info(self, _: Params) -> str:
        identity = self.session.mount.identity
        model = f"{identity.protocol} {identity.model}".strip()
        firmware = f" (firmware {identity.firmware})" if identity.firmware else ""
        return (
            f"scopelink {scopelink_version} ASCOM Alpaca telescope server; mount: {model}{firmware}"
        )

    def _device_state(self, _: Params) -> list[dict[str, object]]:
        # ASCOM: a value that cannot be read is left out. A stale reading is not current.
        session = self.session
        mount = session.mount
        state = mount.state
        flags_fresh = session.is_fresh(position=False)
        values: dict[str, object] = {"AtHome": False}
        if flags_fresh:
            values |= {
                "AtPark": state.parked,
                "IsPulseGuiding": state.pulse_guiding,
                "Slewing": session.slewing,
                "Tracking": state.tracking is not TrackingMode.OFF,
            }
        values["SiderealTime"] = session.sidereal_time()
        values["UTCDate"] = format_utc(mount.now())
        position_fresh = session.is_fresh(position=True)
        if position_fresh and state.alt_deg is not None and state.az_deg is not None:
            values["Altitude"] = state.alt_deg
            values["Azimuth"] = state.az_deg
        ra, dec = session.radec_if_known(state)
        if position_fresh and ra is not None and dec is not None:
            values["RightAscension"] = ra
            values["Declination"] = dec
        if position_fresh and mount.capabilities.can_report_pier_side:
            values["SideOfPier"] = int(state.pier_side)
        values["TimeStamp"] = format_utc(state.read_at)[:-1]  # ASCOM: local-less ISO stamp
        return [{"Name": name, "Value": value} for name, value in values.items()]

    def _action(self, params: Params) -> None:
        name = params.optional("Action") or ""
        raise AlpacaError(
            ErrorNumber.ACTION_NOT_IMPLEMENTED,
            f"action {name!r} is not supported (SupportedActions is empty)",
        )
