"""Issue #12, part 1, in ``scopelink serve`` and the settings file: ``--allowed-host`` and
``allowed_hosts``, Alpaca's own client networks (``--alpaca-allow``, ``[servers.alpaca] allow``,
the local subnets by default beyond loopback), and the pairing link's QR code."""

from __future__ import annotations

from pathlib import Path

import pytest

from scopelink.cli.config import ConfigError, parse_config
from scopelink.cli.errors import CommandError
from scopelink.cli.main import build_parser
from scopelink.cli.serve_command import ServePlan, _qr_lines, plan_from
from scopelink.servers.access import parse_network
from scopelink.servers.hosts import local_networks


def plan(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, *args: str, config: str = ""
) -> ServePlan:
    path = tmp_path / "config.toml"
    path.write_text(config, encoding="utf-8")
    monkeypatch.setenv("SCOPELINK_CONFIG", str(path))
    return plan_from(build_parser().parse_args(["serve", *args]))[1]


def test_alpaca_admits_the_local_subnets_by_default_beyond_loopback(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # planned only: nothing listens, so no address beyond loopback is ever bound here
    wide = plan(tmp_path, monkeypatch, "--host", "0.0.0.0")
    assert wide.alpaca_access.allow == local_networks()
    assert wide.access.allow == ()  # the other servers: as before
    local = plan(tmp_path, monkeypatch)
    assert local.alpaca_access.allow == ()


def test_alpaca_allow_flags_and_config_replace_the_default(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    flagged = plan(tmp_path, monkeypatch, "--host", "0.0.0.0", "--alpaca-allow", "10.1.0.0/16")
    assert flagged.alpaca_access.allow == (parse_network("10.1.0.0/16"),)
    config = '[servers]\nhost = "0.0.0.0"\n[servers.alpaca]\nport = 0\nallow = ["10.2.0.0/16"]\n'
    configured = plan(tmp_path, monkeypatch, config=config)
    assert configured.alpaca == 0
    assert configured.alpaca_access.allow == (parse_network("10.2.0.0/16"),)
    general = plan(tmp_path, monkeypatch, "--host", "0.0.0.0", "--allow", "10.3.0.0/16")
    assert general.alpaca_access.allow == (parse_network("10.3.0.0/16"),)


def test_allowed_hosts_come_from_flags_and_the_file(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    config = '[servers]\nallowed_hosts = ["scope.lan"]\n'
    both = plan(tmp_path, monkeypatch, "--allowed-host", "proxy.example", config=config)
    assert both.allowed_hosts == ("proxy.example", "scope.lan")


def test_bad_values_are_one_line_errors(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    with pytest.raises(CommandError, match="--alpaca-allow"):
        plan(tmp_path, monkeypatch, "--alpaca-allow", "not-a-network")
    for text, key in (
        ('[servers]\nallowed_hosts = "scope.lan"\n', "servers.allowed_hosts"),
        ('[servers]\nallowed_hosts = ["a b"]\n', "servers.allowed_hosts"),
        ('[servers.alpaca]\nallow = ["x"]\n', "servers.alpaca.allow"),
        ("[servers.alpaca]\nprot = 1\n", "servers.alpaca.prot"),
    ):
        with pytest.raises(ConfigError, match=key.replace(".", r"\.")):
            parse_config(text, tmp_path / "c.toml")


def test_the_pairing_link_is_drawn_as_a_qr_code() -> None:
    lines = _qr_lines("http://192.168.1.20:8080/pair?token=abc")
    assert len(lines) >= 12
    assert len({len(line) for line in lines}) == 1  # a square block of text
    assert any("█" in line or "▀" in line or "▄" in line for line in lines)
