"""The settings file: what it may say, the errors a bad value gives, and ``scopelink config``."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from scopelink.cli.config import (
    DEFAULT_SERVER_PORTS,
    Config,
    ConfigError,
    config_path,
    load_config,
)
from scopelink.cli.config_command import EXAMPLE_CONFIG, show
from tests.support.cli import scopelink


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "config.toml"
    path.write_text(text, encoding="utf-8")
    return path


def test_a_missing_file_gives_every_default(tmp_path: Path) -> None:
    config = load_config(tmp_path / "absent.toml")
    assert config == Config(path=None)
    assert config.device is None
    assert config.limits.horizon_deg == 0.0
    assert config.servers.synscan == DEFAULT_SERVER_PORTS["synscan"]
    assert config.servers.host == "127.0.0.1"


def test_the_example_file_reads_back_as_it_says(tmp_path: Path) -> None:
    config = load_config(write(tmp_path, EXAMPLE_CONFIG))
    assert config.device == "synscan:/dev/ttyUSB0"
    assert (config.site.latitude_deg, config.site.longitude_deg) == (40.4, -3.7)
    assert config.site.elevation_m == 650.0
    assert config.site_configured
    assert config.limits.horizon_deg == 10.0
    assert config.limits.horizon_profile == ((0.0, 15.0), (90.0, 25.0), (200.0, 12.0))
    assert config.limits.horizon_at(90.0) == 25.0
    assert config.limits.max_altitude_deg == 88.0
    assert config.servers.alpaca == 11111
    assert config.servers.lx200 == 4030


def test_show_writes_toml_that_reads_back_the_same(tmp_path: Path) -> None:
    original = load_config(write(tmp_path, EXAMPLE_CONFIG + "\n"))
    shown = show(original)
    assert tomllib.loads(shown)  # valid TOML
    again = load_config(write(tmp_path, shown))
    assert (again.device, again.site, again.limits, again.servers) == (
        original.device,
        original.site,
        original.limits,
        original.servers,
    )


def test_a_server_can_be_turned_off(tmp_path: Path) -> None:
    config = load_config(write(tmp_path, "[servers]\nlx200 = false\nalpaca = 0\n"))
    assert config.servers.lx200 is None
    assert config.servers.alpaca == 0  # 0: the OS picks a free port
    assert "lx200 = false" in show(config)


@pytest.mark.parametrize(
    ("text", "key", "expected"),
    [
        ("device = 5\n", "device", "expected a device string"),
        ("[site]\nlatitude = 'north'\nlongitude = 0\n", "site.latitude", "expected a number"),
        ("[site]\nlatitude = true\nlongitude = 0\n", "site.latitude", "expected a number"),
        ("[site]\nlatitude = 40\n", "site.longitude", "missing"),
        ("[site]\nlatitude = 95\nlongitude = 0\n", "site.latitude", "must be in [-90, 90]"),
        ("[site]\nlatitud = 40\n", "site.latitud", "unknown key"),
        ("[horizon]\naltitude = 'low'\n", "horizon.altitude", "expected a number"),
        ("[horizon]\naltitude = 95\n", "horizon.altitude", "horizon 95.0°"),
        ("[horizon]\nprofile = [[0, 10], [90]]\n", "horizon.profile[1]", "[azimuth, altitude]"),
        ("[horizon]\nprofile = [[90, 10], [0, 5]]\n", "horizon.profile", "increasing"),
        ("[limits]\nmax_altitude = 5\n[horizon]\naltitude = 10\n", "limits.max_altitude", "above"),
        ("[servers]\nsynscan = 70000\n", "servers.synscan", "TCP port 0-65535"),
        ("[servers]\nsynscan = '11880'\n", "servers.synscan", "TCP port"),
        ("[servers]\nhost = 1\n", "servers.host", "expected an address"),
        ("site = 'Madrid'\n", "site", "expected a table"),
        ("serial = '/dev/ttyUSB0'\n", "serial", "unknown key"),
    ],
)
def test_a_bad_value_names_the_file_the_key_and_what_was_expected(
    tmp_path: Path, text: str, key: str, expected: str
) -> None:
    path = write(tmp_path, text)
    with pytest.raises(ConfigError) as raised:
        load_config(path)
    message = str(raised.value)
    assert message.startswith(f"{path}: {key}: "), message
    assert expected in message


def test_broken_toml_names_the_file(tmp_path: Path) -> None:
    path = write(tmp_path, "device = \n")
    with pytest.raises(ConfigError, match=r"not valid TOML"):
        load_config(path)


def test_the_environment_variable_overrides_the_path(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("SCOPELINK_CONFIG", str(tmp_path / "mine.toml"))
    assert config_path() == tmp_path / "mine.toml"
    monkeypatch.delenv("SCOPELINK_CONFIG")
    assert config_path().name == "config.toml"
    assert "scopelink" in str(config_path())


def test_a_bad_file_fails_a_device_command_with_one_line(tmp_path: Path) -> None:
    path = write(tmp_path, "[site]\nlatitude = 'north'\nlongitude = 0\n")
    result = scopelink(path, "status", "--device", "sim")
    assert result.returncode == 1
    lines = result.stderr.strip().splitlines()
    assert lines[0] == f"scopelink status: {path}: site.latitude: expected a number, got 'north'"
    assert lines[1].startswith("  hint: fix the file, or point SCOPELINK_CONFIG")
    assert len(lines) == 2


def test_config_path_and_show_commands(tmp_path: Path) -> None:
    path = write(tmp_path, 'device = "sim:az-gti"\n[site]\nlatitude = 40.4\nlongitude = -3.7\n')
    shown_path = scopelink(path, "config", "path")
    assert shown_path.returncode == 0
    assert shown_path.stdout.strip() == str(path)
    shown = scopelink(path, "config", "show")
    assert shown.returncode == 0, shown.stderr
    settings = tomllib.loads(shown.stdout)
    assert settings["device"] == "sim:az-gti"
    assert settings["site"]["latitude"] == 40.4


def test_flags_override_the_file(tmp_path: Path) -> None:
    path = write(tmp_path, 'device = "sim:az-gti"\n[site]\nlatitude = -33.9\nlongitude = 18.4\n')
    from_file = scopelink(path, "info", "--json")
    assert from_file.returncode == 0, from_file.stderr
    assert '"model": "AZ-GTi"' in from_file.stdout
    overridden = scopelink(path, "status", "--json", "--device", "sim:eq6", "--site", "10,20")
    assert overridden.returncode == 0, overridden.stderr
    # An EQ6 at power-on points at the pole: its altitude is the (flag's) latitude.
    assert '"alt_deg": 10.0' in overridden.stdout


# --- properties --------------------------------------------------------------------------------

toml_scalars = st.one_of(
    st.booleans(),
    st.integers(-(2**40), 2**40),
    st.floats(allow_nan=False, allow_infinity=False, width=32),
    st.text(st.characters(blacklist_categories=("Cs", "Cc")), max_size=12),
)


@settings(max_examples=60, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    latitude=st.floats(-90, 90),
    longitude=st.floats(-180, 180),
    horizon=st.floats(-10, 60),
    port=st.integers(0, 65535),
)
def test_valid_values_read_back(
    tmp_path: Path, latitude: float, longitude: float, horizon: float, port: int
) -> None:
    text = (
        f"[site]\nlatitude = {latitude!r}\nlongitude = {longitude!r}\n"
        f"[horizon]\naltitude = {horizon!r}\n[servers]\nsynscan = {port}\n"
    )
    config = load_config(write(tmp_path, text))
    assert (config.site.latitude_deg, config.site.longitude_deg) == (latitude, longitude)
    assert config.limits.horizon_deg == horizon
    assert config.servers.synscan == port


@settings(max_examples=80, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    key=st.sampled_from(
        [
            ("", "device"),
            ("site", "latitude"),
            ("horizon", "altitude"),
            ("horizon", "profile"),
            ("limits", "max_altitude"),
            ("servers", "alpaca"),
            ("servers", "host"),
        ]
    ),
    value=st.one_of(toml_scalars, st.lists(toml_scalars, max_size=3)),
)
def test_any_value_either_loads_or_is_a_config_error(
    tmp_path: Path, key: tuple[str, str], value: object
) -> None:
    """Whatever a key holds, reading the file never fails with anything but a ConfigError."""
    table, name = key
    data: dict[str, object] = {name: value}
    if table == "site":
        data["longitude"] = 0.0
    lines = [f"[{table}]"] if table else []
    lines += [f"{k} = {_toml(v)}" for k, v in data.items()]
    path = write(tmp_path, "\n".join(lines) + "\n")
    message = ""
    try:
        load_config(path)
    except ConfigError as error:
        message = str(error)
    assert not message or message.startswith(f"{path}: ")


def _toml(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)  # a JSON string is a valid TOML basic string
    if isinstance(value, list):
        return "[" + ", ".join(_toml(item) for item in value) + "]"
    return repr(value)
