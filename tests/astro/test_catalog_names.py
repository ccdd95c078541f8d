"""Catalogue names: normalisation, lookup by every kind of name, suggestions, search."""

from __future__ import annotations

import statistics
import time
from datetime import UTC, datetime

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from scopelink.astro.catalog import (
    CatalogObject,
    ObjectKind,
    UnknownObjectError,
    default_catalogue,
    find,
    lookup,
    name_key,
    search,
)

WHEN = datetime(2026, 1, 1, tzinfo=UTC)


@pytest.mark.parametrize(
    ("text", "key"),
    [
        ("M 31", "M31"),
        ("m31", "M31"),
        ("M031", "M31"),
        ("Messier 31", "M31"),
        ("NGC 0224", "NGC224"),
        ("ngc  224", "NGC224"),
        ("Caldwell 14", "C14"),
        ("ESO 56-115", "ESO56-115"),
        ("ESO056-115", "ESO56-115"),
        ("Pléiades", "PLEIADES"),
        ("Brocchi's Cluster", "BROCCHISCLUSTER"),
        ("HIP 0091262", "HIP91262"),
        ("NGC 0", "NGC0"),
        ("  ", ""),
    ],
)
def test_name_key(text: str, key: str) -> None:
    assert name_key(text) == key


@pytest.mark.parametrize(
    ("text", "name"),
    [
        ("m 31", "M 31"),
        ("M31", "M 31"),
        ("messier 31", "M 31"),
        ("NGC 224", "M 31"),
        ("Andromeda Galaxy", "M 31"),
        ("orion nebula", "M 42"),
        ("NGC7000", "NGC 7000"),
        ("ngc 7000", "NGC 7000"),
        ("North America Nebula", "NGC 7000"),
        ("C 20", "NGC 7000"),
        ("IC 434", "IC 434"),
        ("ic434", "IC 434"),
        ("Caldwell 14", "C 14"),
        ("C14", "C 14"),
        ("Double Cluster", "C 14"),
        ("M 45", "M 45"),
        ("Pleiades", "M 45"),
        ("Horsehead Nebula", "Horsehead Nebula"),
        ("B 33", "Horsehead Nebula"),
        ("IC 11", "NGC 281"),  # an OpenNGC duplicate record folds into its main object
        ("M 102", "M 101"),  # OpenNGC's reading of the M 102 ambiguity
        ("Vega", "Vega"),
        ("VEGA", "Vega"),
        ("HIP 91262", "Vega"),
        ("Polaris", "Polaris"),
        ("Rigil Kentaurus", "Rigil Kentaurus"),
        ("rigilkentaurus", "Rigil Kentaurus"),
        ("Agena", "Hadar"),  # a variant name leads to the IAU name
        ("HIP 1", "HIP 1"),
        ("Sun", "Sun"),
        ("moon", "Moon"),
        ("MARS", "Mars"),
        ("Pluto", "Pluto"),
    ],
)
def test_lookup_by_name(text: str, name: str) -> None:
    assert lookup(text, WHEN).name == name


def test_every_caldwell_and_messier_number_resolves() -> None:
    for number in range(1, 111):
        assert find(f"M {number}").kind is ObjectKind.DEEP_SKY, number
    for number in range(1, 110):
        assert find(f"Caldwell {number}").kind is ObjectKind.DEEP_SKY, number


def test_every_named_star_has_a_hipparcos_number() -> None:
    stars = [
        entry
        for entry in {id(e): e for e in map(find, _star_names())}.values()
        if entry.kind is ObjectKind.STAR
    ]
    assert len(stars) == 108
    for star in stars:
        hip_aliases = [a for a in star.aliases if a.startswith("HIP ")]
        assert len(hip_aliases) == 1, star.name
        assert find(hip_aliases[0]) is star


def _star_names() -> list[str]:
    import ephem.stars

    return [line.split(",")[0] for line in ephem.stars.db.strip().splitlines()]


@pytest.mark.parametrize("text", ["HIP 0", "HIP 120417", "HIP 99999999", "HIP"])
def test_hip_numbers_outside_hipparcos_are_unknown(text: str) -> None:
    with pytest.raises(UnknownObjectError):
        find(text)


@pytest.mark.parametrize(
    ("typo", "meant"),
    [
        ("Vgea", "Vega"),
        ("M 3l", "M 31"),
        ("NGC 7OOO", "NGC 7000"),
        ("Betelguese", "Betelgeuse"),
        ("Andromeda", "Andromeda Galaxy"),
        ("Jupiterr", "Jupiter"),
        ("Plaeides", "Pleiades"),
    ],
)
def test_near_misses_suggest_the_intended_name(typo: str, meant: str) -> None:
    with pytest.raises(UnknownObjectError) as caught:
        find(typo)
    assert caught.value.suggestions[0] == meant
    assert caught.value.name == typo
    message = str(caught.value)
    assert repr(typo) in message
    assert f"did you mean {meant!r}" in message


def test_nonsense_gets_a_hint_instead_of_suggestions() -> None:
    with pytest.raises(UnknownObjectError, match="try a Messier, NGC") as caught:
        find("?!")
    assert caught.value.suggestions == ()


@settings(max_examples=150, deadline=None)
@given(
    st.one_of(
        st.text(max_size=30),
        st.text(alphabet="MNGCIHPlO0123456789 -", max_size=10),
    )
)
def test_any_text_finds_an_object_or_raises_unknown_object(text: str) -> None:
    outcome: CatalogObject | UnknownObjectError
    try:
        outcome = lookup(text, WHEN)
    except UnknownObjectError as error:
        outcome = error
    if isinstance(outcome, UnknownObjectError):
        assert outcome.name == text
        assert len(outcome.suggestions) <= 5
    else:
        assert name_key(text) != ""
        assert 0.0 <= outcome.ra_hours < 24.0
        assert -90.0 <= outcome.dec_deg <= 90.0


@pytest.mark.parametrize(
    ("prefix", "first"),
    [
        ("m 3", "M 3"),
        ("M31", "M 31"),
        ("ve", "Venus"),  # the solar system first, then bright named objects
        ("veg", "Vega"),
        ("ngc 700", "NGC 700"),
        ("androm", "M 31"),
        ("sat", "Saturn"),
    ],
)
def test_search_puts_the_best_match_first(prefix: str, first: str) -> None:
    assert search(prefix, 5)[0].name == first


def test_search_lists_each_object_once_and_respects_the_limit() -> None:
    results = search("M", 20)
    assert len(results) == 20
    assert len({r.name for r in results}) == 20
    assert search("M 4", 3) == search("M 4", 10)[:3]
    assert search("", 10) == []
    assert search("M", 0) == []
    assert search("zzzzzz", 10) == []


def test_search_fills_the_limit_when_objects_have_many_matching_aliases() -> None:
    # Every Messier object also matches "M" through "MCG ..." or "MWSC ..." identifiers.
    results = search("M", 200)
    assert len(results) == 200
    assert len({r.name for r in results}) == 200
    assert len(default_catalogue()) > 13_000


def test_search_reports_the_alias_that_matched() -> None:
    (match,) = [m for m in search("orion neb", 10) if m.name == "M 42"]
    assert match.matched == "Orion Nebula"
    assert match.kind is ObjectKind.DEEP_SKY
    assert match.magnitude == pytest.approx(4.0)


def test_search_is_fast_enough_for_every_keystroke() -> None:
    default_catalogue()  # the one-time load
    prefixes = ["m", "m3", "m31", "n", "ng", "ngc", "ngc7", "ngc70", "v", "ve", "c", "c1", "ic4"]
    prefixes += ["s", "sa", "h", "hip", "a", "an", "and", "orion", "p", "pl", "ple", "b", "be"]
    durations = []
    for prefix in prefixes * 5:
        started = time.perf_counter()
        search(prefix, 10)
        durations.append(time.perf_counter() - started)
    assert statistics.median(durations) < 0.005
    assert max(durations) < 0.05
