"""Object names as lookup keys: case-, space- and zero-padding-insensitive.

``"M 31"``, ``"m31"``, ``"Messier 31"`` and ``"M031"`` share the key ``M31``; ``"NGC 0224"`` and
``"ngc224"`` the key ``NGC224``. A key is the name's letter and digit runs, upper-cased, with
leading zeros dropped from numbers; two numbers in a row keep a ``-`` between them so that
``"ESO 56-115"`` does not become ``ESO56115``. Accents are folded (``"Pléiades"`` = ``PLEIADES``).
"""

from __future__ import annotations

import re
import unicodedata

__all__ = ["confusable_variants", "name_key"]

_RUNS = re.compile(r"[A-Z]+|[0-9]+")

# Catalogue words people spell out, mapped to the abbreviation the data uses.
_CATALOGUE_WORDS = {
    "MESSIER": "M",
    "CALDWELL": "C",
    "HIPPARCOS": "HIP",
    "MELOTTE": "MEL",
    "INDEXCATALOGUE": "IC",
}


def name_key(text: str) -> str:
    """The lookup key of an object name (empty when the text has no letters or digits)."""
    if not text.isascii():
        text = unicodedata.normalize("NFKD", text).encode("ascii", "ignore").decode("ascii")
    runs = _RUNS.findall(text.upper())
    if runs and runs[0] in _CATALOGUE_WORDS:
        runs[0] = _CATALOGUE_WORDS[runs[0]]
    key: list[str] = []
    previous_was_number = False
    for run in runs:
        is_number = run.isdigit()
        if is_number and previous_was_number:
            key.append("-")
        key.append((run.lstrip("0") or "0") if is_number else run)
        previous_was_number = is_number
    return "".join(key)


# Letters typed for digits (and back) next to a number: "M 3l" means M 31, "NGC 7OOO" NGC 7000.
_LOOKALIKE_DIGITS = str.maketrans({"L": "1", "I": "1", "O": "0", "S": "5", "B": "8", "Z": "2"})


def confusable_variants(text: str) -> list[str]:
    """Keys ``text`` may have meant if some letters standing among digits were digits.

    Only the part after the first digit is rewritten, so catalogue prefixes stay as typed.
    """
    upper = unicodedata.normalize("NFKD", text).upper()
    first_digit = next((i for i, char in enumerate(upper) if char.isdigit()), None)
    if first_digit is None:
        return []
    rewritten = upper[:first_digit] + upper[first_digit:].translate(_LOOKALIKE_DIGITS)
    variant = name_key(rewritten)
    return [variant] if variant != name_key(text) else []
