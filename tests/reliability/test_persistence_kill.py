"""``kill -9`` at random points loses nothing: the settings file, Alpaca's UniqueID, the Sky
Commander's object store (docs/reliability-persistence.md).

Each test kills a real child process that writes in a loop (tests/support/persistence.py)
dozens of times at seeded random delays and checks, after every kill, that the file is whole and
parseable, holds the last acknowledged write or the one in flight, and that at most one
temporary file was left behind (removed by the next write).
"""

from __future__ import annotations

import json
import os
import uuid
from collections.abc import Iterator
from pathlib import Path

import pytest

from scopelink.cli.config import load_config
from scopelink.cli.config_command import EXAMPLE_CONFIG
from scopelink.cli.config_edit import set_values
from scopelink.links.storage import temporaries_of
from scopelink.servers.alpaca.identity import UNIQUE_ID_FILE, load_or_create_unique_id
from scopelink.servers.skytracker import ObjectStore, StoredObject
from scopelink.servers.skytracker.objects import OBJECTS_FILE
from tests.support.persistence import KillRound, Zygote, delays, devices_for, stored_object_for

KILLS = int(os.environ.get("SCOPELINK_KILLS", "30"))
"""Kills per writer; the soak in docs/reliability-persistence.md sets more."""


@pytest.fixture(scope="module")
def zygote() -> Iterator[Zygote]:
    forker = Zygote()
    yield forker
    forker.close()


def kill_round(
    zygote: Zygote, writer: str, arguments: list[object], delay_s: float, tmp: Path
) -> KillRound:
    killed = zygote.run_and_kill(writer, arguments, delay_s, tmp / "acknowledged.txt")
    assert killed.killed_while_running, f"the {writer} writer died by itself (see stderr)"
    return killed


def numbers_of(acknowledged: list[str], first: int) -> list[int]:
    """The acknowledged write numbers, checked to be ``first``, ``first + 1``, ... (no errors)."""
    assert all(ack.isdigit() for ack in acknowledged), acknowledged
    numbers = [int(ack) for ack in acknowledged]
    assert numbers == list(range(first, first + len(numbers)))
    return numbers


def test_config_set_killed_at_random_points_keeps_the_file_whole(
    tmp_path: Path, zygote: Zygote
) -> None:
    path = tmp_path / "config.toml"
    path.write_text(EXAMPLE_CONFIG, encoding="utf-8")
    comments = [line.split("#", 1)[1] for line in EXAMPLE_CONFIG.splitlines() if "#" in line]
    on_disk = (650.0, "synscan:/dev/ttyUSB0")  # what the example says
    first = 1000
    leftovers = in_flight_landed = acknowledged_total = 0
    for delay in delays(seed=61, count=KILLS, low_s=0.01, high_s=0.2):
        killed = kill_round(zygote, "config", [str(path), first], delay, tmp_path)
        numbers = numbers_of(killed.acknowledged, first)
        acknowledged_total += len(numbers)
        text = path.read_text(encoding="utf-8")
        config = load_config(path)  # whole and valid: the reader every command uses accepts it
        found = (config.site.elevation_m, config.device)
        last_acknowledged = (float(numbers[-1]), devices_for(numbers[-1])) if numbers else on_disk
        flying = first + len(numbers)
        in_flight = (float(flying), devices_for(flying))
        assert found in (last_acknowledged, in_flight), (killed, found)
        in_flight_landed += found == in_flight
        # Every comment of the user's file survives every rewrite.
        assert all(comment in text for comment in comments)
        stale = temporaries_of(path)
        assert len(stale) <= 1, stale
        leftovers += len(stale)
        on_disk = found
        first = int(found[0]) + 1
    print(
        f"config: {acknowledged_total} acknowledged, {in_flight_landed} unacknowledged writes "
        f"landed, {leftovers} leftover temporaries"
    )
    # The kills landed among writes, not all before the first (loose: CI machines are slow).
    assert acknowledged_total >= KILLS // 3
    set_values(path, [("site.elevation", "1")])  # the next write cleans a dead writer's leftover
    assert temporaries_of(path) == []
    assert load_config(path).site.elevation_m == 1.0


def test_alpaca_unique_id_is_created_once_and_never_changes(tmp_path: Path, zygote: Zygote) -> None:
    created_unacknowledged = acknowledged = nothing_yet = 0
    state_dir = tmp_path
    known: str | None = None
    identities: dict[Path, str | None] = {}
    short = delays(seed=62, count=KILLS, low_s=0.0, high_s=0.03)  # around the creation
    long = delays(seed=620, count=KILLS, low_s=0.05, high_s=0.3)  # surely after it
    for index in range(KILLS):
        if index % 3 == 0:  # a fresh state directory, then two restarts in it
            state_dir = tmp_path / f"state{index}"
            known = None
        delay = long[index] if index % 3 == 2 else short[index]
        killed = kill_round(zygote, "unique_id", [str(state_dir)], delay, tmp_path)
        path = state_dir / UNIQUE_ID_FILE
        for unique_id in killed.acknowledged:
            known = known or unique_id
            assert unique_id == known  # once served, the identity is forever
        if path.exists():
            stored = json.loads(path.read_text(encoding="utf-8"))["UniqueID"]
            uuid.UUID(stored)
            created_unacknowledged += known is None
            known = known or stored
            assert stored == known
        else:
            assert known is None, "an acknowledged UniqueID was lost"
            nothing_yet += 1
        acknowledged += bool(killed.acknowledged)
        identities[state_dir] = known
        assert len(temporaries_of(path)) <= 1
    print(
        f"UniqueID: {acknowledged} served, {created_unacknowledged} written unacknowledged, "
        f"{nothing_yet} before creation"
    )
    assert acknowledged > 0  # some kills came after the server was up
    for directory, identity in identities.items():  # the next start of every state directory
        final = load_or_create_unique_id(directory)
        assert final == (identity or final)
        assert temporaries_of(directory / UNIQUE_ID_FILE) == []  # leftovers removed


def test_sky_commander_store_killed_at_random_points_loses_no_acknowledged_object(
    tmp_path: Path, zygote: Zygote
) -> None:
    expected: dict[int, StoredObject] = {}
    first = 0
    leftovers = acknowledged_total = 0
    for delay in delays(seed=63, count=KILLS, low_s=0.02, high_s=0.2):
        killed = kill_round(zygote, "commander", [str(tmp_path / "store"), first], delay, tmp_path)
        numbers = numbers_of(killed.acknowledged, first)
        acknowledged_total += len(numbers)
        for number in numbers:
            expected[number % 59] = stored_object_for(number)
        path = tmp_path / "store" / OBJECTS_FILE
        if not path.exists():
            assert not expected, "acknowledged objects were lost"
            continue
        json.loads(path.read_bytes())  # parseable, never torn or empty
        found = ObjectStore(tmp_path / "store").items()
        flying = first + len(numbers)
        with_in_flight = {**expected, flying % 59: stored_object_for(flying)}
        assert found in (expected, with_in_flight), killed
        stale = temporaries_of(path)
        assert len(stale) <= 1, stale
        leftovers += len(stale)
        expected = found
        first = flying + 1
    print(f"commander: {acknowledged_total} acknowledged, {leftovers} leftover temporaries")
    assert acknowledged_total >= KILLS // 3
    assert ObjectStore(tmp_path / "store").items() == expected  # the next start reads it all
    assert temporaries_of(tmp_path / "store" / OBJECTS_FILE) == []  # and removed leftovers
