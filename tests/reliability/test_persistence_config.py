"""``scopelink config set|unset|init``: comments kept, bad results refused before writing, atomic
writes, and the storage helpers under them (docs/reliability-persistence.md)."""

from __future__ import annotations

import dataclasses
import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest
import tomlkit
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scopelink.cli.config import ConfigError, load_config
from scopelink.cli.config_command import EXAMPLE_CONFIG, commented_out
from scopelink.cli.config_edit import parse_value, set_values, unset_keys
from scopelink.links.storage import (
    create_atomically,
    remove_stale_temporaries,
    temporaries_of,
    write_atomically,
)
from tests.support.cli import scopelink_here


def example(tmp_path: Path) -> Path:
    path = tmp_path / "config.toml"
    path.write_text(EXAMPLE_CONFIG, encoding="utf-8")
    return path


def test_set_changes_only_the_value_and_keeps_every_comment(tmp_path: Path) -> None:
    path = example(tmp_path)
    status, out, err = scopelink_here(
        path, "config", "set", "site.latitude", "-33.9", "device", "sim:az-gti"
    )
    assert (status, err) == (0, "")
    assert out.splitlines() == [  # what changed, as the user named it
        "site.latitude: 40.4 -> -33.9",
        'device: "synscan:/dev/ttyUSB0" -> "sim:az-gti"',
        f"(in {path})",
    ]
    text = path.read_text(encoding="utf-8")
    before, after = EXAMPLE_CONFIG.splitlines(), text.splitlines()
    changed = [(old, new) for old, new in zip(before, after, strict=True) if old != new]
    assert [new.split("#")[0].strip() for _, new in changed] == [
        'device = "sim:az-gti"',
        "latitude = -33.9",
    ]
    # The inline comments of the changed lines are still there.
    assert all(old.split("#", 1)[1] in new for old, new in changed)
    config = load_config(path)
    assert (config.device, config.site.latitude_deg) == ("sim:az-gti", -33.9)


def test_set_on_a_missing_file_creates_one_that_loads(tmp_path: Path) -> None:
    path = tmp_path / "sub" / "config.toml"
    status, _, err = scopelink_here(
        path, "config", "set", "site.latitude", "40.4", "site.longitude", "-3.7"
    )
    assert status == 0, err
    text = path.read_text(encoding="utf-8")
    assert text.startswith("# scopelink settings")
    assert text.endswith("\n")
    assert load_config(path).site.longitude_deg == -3.7


@pytest.mark.parametrize(
    ("arguments", "key", "problem"),
    [
        (("site.latitude", "95"), "site", "latitude"),
        (("site.latitud", "4"), "site.latitud", "unknown key"),
        (("horizon.altitude", "north"), "horizon.altitude", "expected a number"),
        (("servers.alpaca", "70000"), "servers.alpaca", "TCP port"),
        (("device", "true"), "device", "expected a device string"),
        (("device", "''"), "device", "expected a device string"),
        (("servers", "1"), "servers", "expected a table"),
        (("limits.max_altitude.x", "1"), "limits.max_altitude", "holds a value"),
        (("site..latitude", "1"), "site..latitude", "dotted key"),
    ],
)
def test_a_change_that_would_not_load_is_refused_and_the_file_is_untouched(
    tmp_path: Path, arguments: tuple[str, str], key: str, problem: str
) -> None:
    path = example(tmp_path)
    before = path.read_bytes()
    status, _, err = scopelink_here(path, "config", "set", *arguments)
    assert status == 1
    first, hint = err.splitlines()
    assert first.startswith(f"scopelink config: {path}: {key}")
    assert problem in first
    assert "is unchanged" in hint
    assert path.read_bytes() == before
    assert temporaries_of(path) == []


def test_a_file_broken_by_hand_can_be_repaired_with_set(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text("[site]\nlatitude = 'north'  # oops\nlongitude = 0\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"site\.latitude"):
        load_config(path)
    set_values(path, [("site.latitude", "12.5")])
    assert path.read_text(encoding="utf-8") == "[site]\nlatitude = 12.5  # oops\nlongitude = 0\n"


def test_a_file_that_is_not_toml_is_never_rewritten(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    path.write_text("[site\nlatitude = 1\n", encoding="utf-8")
    with pytest.raises(ConfigError, match="not valid TOML"):
        set_values(path, [("device", "sim")])
    assert path.read_text(encoding="utf-8") == "[site\nlatitude = 1\n"


def test_unset_removes_a_value_a_table_and_an_emptied_table(tmp_path: Path) -> None:
    path = example(tmp_path)
    unset_keys(path, ["horizon.profile", "servers"])
    text = path.read_text(encoding="utf-8")
    assert "profile" not in text
    assert "[servers]" not in text
    assert "altitude = 10" in text
    unset_keys(path, ["limits.max_altitude"])  # its only key: the [limits] header goes too
    assert "[limits]" not in path.read_text(encoding="utf-8")
    config = load_config(path)
    assert config.limits.max_altitude_deg == 90.0
    assert config.servers.alpaca == 11111
    with pytest.raises(ConfigError, match=r"horizon\.nope: not set"):
        unset_keys(path, ["horizon.nope"])
    # Unsetting half of what [site] needs would make the file fail to load: refused.
    with pytest.raises(ConfigError, match=r"site\.longitude: missing"):
        unset_keys(path, ["site.longitude"])


def test_init_writes_the_example_once_and_never_overwrites(tmp_path: Path) -> None:
    path = tmp_path / "config.toml"
    status, out, err = scopelink_here(path, "config", "init")
    assert status == 0, err
    assert out.startswith(f"wrote {path}: every setting commented out")
    # issue #18: the example's Madrid site and 10° horizon are not made active settings
    assert path.read_text(encoding="utf-8") == commented_out(EXAMPLE_CONFIG)
    defaults = dataclasses.replace(load_config(tmp_path / "absent.toml"), path=None)
    assert dataclasses.replace(load_config(path), path=None) == defaults
    set_values(path, [("device", "sim")])
    mine = path.read_bytes()
    status, _, err = scopelink_here(path, "config", "init")
    assert status == 1
    assert "exists already; not overwritten" in err
    assert path.read_bytes() == mine
    assert scopelink_here(path, "config", "init", "extra")[0] == 1


def test_set_keeps_the_file_mode_and_edits_a_symlink_where_it_points(tmp_path: Path) -> None:
    real = example(tmp_path)
    real.chmod(0o640)
    link = tmp_path / "link.toml"
    link.symlink_to(real)
    set_values(link, [("device", "sim")])
    assert link.is_symlink()
    assert load_config(real).device == "sim"
    assert stat.S_IMODE(real.stat().st_mode) == 0o640


def test_values_are_toml_or_else_strings() -> None:
    assert parse_value("40.4") == 40.4
    assert parse_value("false") is False
    assert parse_value("[[0, 15], [90, 25]]") == [[0, 15], [90, 25]]
    assert parse_value('"1234"') == "1234"
    assert parse_value("sim:az-gti") == "sim:az-gti"
    assert parse_value("tcp://192.168.4.1:11880") == "tcp://192.168.4.1:11880"
    assert parse_value("1\n[servers]\nalpaca = 1") == "1\n[servers]\nalpaca = 1"
    assert parse_value("1 \nx = 2") == "1 \nx = 2"


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(text=st.text(max_size=60))
def test_any_device_text_is_stored_exactly_or_refused_with_the_key(
    tmp_path: Path, text: str
) -> None:
    path = example(tmp_path)
    before = path.read_bytes()
    refusal = ""
    try:
        set_values(path, [("device", text)])
    except ConfigError as error:
        refusal = str(error)
    if refusal:
        assert refusal.startswith(f"{path}: device")
        assert path.read_bytes() == before
        return
    document = tomlkit.parse(path.read_text(encoding="utf-8"))
    # Whatever the text held (quotes, newlines, brackets), it is one value, not new keys.
    assert sorted(document) == ["device", "horizon", "limits", "servers", "site"]
    stored = load_config(path).device
    value = parse_value(text)
    assert stored == (value.strip() if isinstance(value, str) else value)


def test_a_dead_writers_temporary_is_removed_and_a_live_ones_kept(tmp_path: Path) -> None:
    path = tmp_path / "state.json"
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        check=True,
        capture_output=True,
        text=True,
    )
    dead_pid = int(dead.stdout)
    leftover = tmp_path / f".state.json.{dead_pid}.abcd1234.tmp"
    leftover.write_bytes(b'{"half')
    live = tmp_path / f".state.json.{os.getppid()}.efgh5678.tmp"
    live.write_bytes(b"in progress")
    unrelated = tmp_path / ".other.json.1.x.tmp"
    unrelated.write_bytes(b"")
    assert temporaries_of(path) == sorted([leftover, live])
    write_atomically(path, b"{}")
    assert not leftover.exists()
    assert live.exists()  # its writer (our parent process) is alive: not ours to remove
    assert unrelated.exists()
    assert remove_stale_temporaries(path) == []
    assert path.read_bytes() == b"{}"


def test_create_atomically_never_replaces(tmp_path: Path) -> None:
    path = tmp_path / "new.json"
    create_atomically(path, b"first")
    with pytest.raises(FileExistsError):
        create_atomically(path, b"second")
    assert path.read_bytes() == b"first"
    assert temporaries_of(path) == []
