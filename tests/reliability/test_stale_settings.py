"""The ``stale_after_s`` setting (issue #11 part 5): read from the settings file, checked, applied
to the mount of every device command, documented with the default the code has; and the poller's
back-off that bounds how soon a returning device is polled again (part 6)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from scopelink.astro import Site
from scopelink.cli.config import ConfigError, parse_config
from scopelink.cli.config_command import EXAMPLE_CONFIG, show
from scopelink.cli.mount_session import DeviceCommand, open_device
from scopelink.drivers.open import parse_device
from scopelink.mount import DEFAULT_STALE_AFTER_S
from scopelink.mount.polling import (
    MAX_RETRY_S,
    MAX_STALE_AFTER_S,
    MIN_STALE_AFTER_S,
    StateBroadcast,
    StatePoller,
)
from scopelink.mount.types import MountState
from scopelink.sim import EQ6, SimulatedMount

DOCS = Path(__file__).resolve().parents[2] / "docs"
SITE = Site(latitude_deg=48.0, longitude_deg=11.0)


def test_the_file_sets_it_and_a_missing_key_gives_the_default(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    assert parse_config("", path).stale_after_s == DEFAULT_STALE_AFTER_S
    assert parse_config("[readings]\nstale_after_s = 3\n", path).stale_after_s == 3.0
    assert "stale_after_s = 3.0" in show(parse_config("[readings]\nstale_after_s = 3\n", path))


@pytest.mark.parametrize("value", ["0", "0.1", "5.5", "60", "true", '"2"', "nan", "-1", "[2]"])
def test_values_outside_the_range_are_refused_naming_the_key(tmp_path: Path, value: str) -> None:
    path = tmp_path / "config.toml"
    with pytest.raises(ConfigError, match=r"readings\.stale_after_s"):
        parse_config(f"[readings]\nstale_after_s = {value}\n", path)


def test_unknown_keys_in_the_table_are_refused(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"readings\.stale_after: unknown key"):
        parse_config("[readings]\nstale_after = 2\n", tmp_path / "config.toml")


def test_a_mount_refuses_a_setting_outside_the_range() -> None:
    mount = SimulatedMount(EQ6, site=SITE)
    assert mount.stale_after_s == DEFAULT_STALE_AFTER_S
    for bad in (MIN_STALE_AFTER_S / 2, MAX_STALE_AFTER_S + 0.1, float("nan")):
        with pytest.raises(ValueError, match="stale_after_s"):
            mount.stale_after_s = bad
    mount.stale_after_s = MAX_STALE_AFTER_S
    assert mount.stale_after_s == MAX_STALE_AFTER_S


async def test_device_commands_apply_the_setting(tmp_path: Path) -> None:
    config = parse_config("[readings]\nstale_after_s = 4.5\n", tmp_path / "config.toml")
    command = DeviceCommand(parse_device("sim"), SITE, config, 1.0, None)
    mount = await open_device(command)
    try:
        assert mount.stale_after_s == 4.5
    finally:
        await mount.disconnect()


def test_the_docs_and_the_example_state_the_default_the_code_has() -> None:
    default = f"{DEFAULT_STALE_AFTER_S:g}"
    safety = (DOCS / "reliability-safety.md").read_text(encoding="utf-8")
    assert f"`stale_after_s`, **default {default} s**" in safety
    assert f"**{MIN_STALE_AFTER_S:g}-{MAX_STALE_AFTER_S:g} s**" in safety
    assert f"at most `MAX_RETRY_S` = **{MAX_RETRY_S:g} s**" in safety
    cli = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert f"`readings.stale_after_s` (default **{default} s**" in cli
    assert re.search(rf"stale_after_s = {DEFAULT_STALE_AFTER_S}\b", cli)
    assert re.search(rf"# stale_after_s = {DEFAULT_STALE_AFTER_S}\b", EXAMPLE_CONFIG)
    for page in ("alpaca.md", "lx200.md", "stellarium.md"):
        text = (DOCS / page).read_text(encoding="utf-8")
        assert f"({default} s by default)" in text or f"(default {default} s)" in text, page


def test_the_poller_backs_off_by_doubling_up_to_its_cap() -> None:
    async def refresh() -> MountState:
        raise AssertionError("not called")

    poller = StatePoller(
        refresh,
        lambda: True,
        lambda _: None,
        StateBroadcast(MountState(read_at=SimulatedMount(EQ6, site=SITE).now())),
        interval_s=0.0,
        retry_s=0.5,
    )
    delays = []
    for failures in range(1, 7):
        poller.failures_in_a_row = failures
        delays.append(poller.backoff_s())
    assert delays == [0.5, 1.0, 2.0, 2.0, 2.0, 2.0]
    assert max(delays) == MAX_RETRY_S
