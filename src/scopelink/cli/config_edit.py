"""Changing the settings file from the command line: ``config set``, ``unset`` and ``init``.

The file is edited with tomlkit, which keeps the user's comments, order and spacing; only the
value asked for changes. The edited text is checked with the same reader every command uses
(:func:`scopelink.cli.config.parse_config`) before anything is written, so a change that would
make the file unreadable is refused with the key and the reason, and the file stays as it was.
Writes are atomic (:mod:`scopelink.links.storage`): a crash or ``kill -9`` leaves the old file
or the new one, never a torn one.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

import tomlkit
import tomlkit.exceptions
from tomlkit.container import Container
from tomlkit.items import Table

from scopelink.cli.config import ConfigError, parse_config
from scopelink.links.storage import create_atomically, write_atomically

__all__ = ["create_config", "parse_value", "set_values", "unset_keys"]

NEW_FILE_HEADER: Final = "# scopelink settings (TOML; 'scopelink config example' shows every key)\n"


def parse_value(text: str) -> Any:
    """A command-line VALUE as TOML (``40.4``, ``false``, ``[[0, 15]]``, ``"1234"``), else a string.

    So ``device sim`` and ``servers.host 0.0.0.0`` need no quotes; quote a string that looks
    like a number or a boolean (``'"true"'``).
    """
    if "\n" in text or "\r" in text:
        return text  # one value, never extra lines (keys) smuggled into the file
    try:
        document = tomlkit.parse(f"value = {text}")
    except tomlkit.exceptions.ParseError:
        return text
    if list(document) != ["value"]:
        return text
    return document["value"]


def set_values(path: Path, assignments: Sequence[tuple[str, str]]) -> str:
    """Set each dotted KEY to VALUE in one write (so ``site.latitude`` and ``site.longitude``
    can arrive together); returns the new text. Nothing is written if the result is invalid."""
    document = _read_document(path)
    for key, value in assignments:
        parts = _key_parts(path, key)
        table: Container | Table | dict[str, Any] = document
        for index, part in enumerate(parts[:-1]):
            child = table.get(part)
            if child is None:
                child = tomlkit.table()
                table[part] = child
                child = table[part]
            elif not isinstance(child, dict):
                raise ConfigError(
                    f"{path}: {'.'.join(parts[: index + 1])}: holds a value, not a table"
                )
            table = child
        table[parts[-1]] = parse_value(value)
    return _check_and_write(path, document)


def unset_keys(path: Path, keys: Sequence[str]) -> str:
    """Remove each dotted KEY (a table and everything in it, or one value); a table left empty
    goes too. Returns the new text; a key that is not in the file is an error."""
    document = _read_document(path)
    for key in keys:
        parts = _key_parts(path, key)
        chain: list[Container | Table | dict[str, Any]] = [document]
        for part in parts[:-1]:
            child = chain[-1].get(part)
            if not isinstance(child, dict):
                raise ConfigError(f"{path}: {key}: not set in the file")
            chain.append(child)
        if parts[-1] not in chain[-1]:
            raise ConfigError(f"{path}: {key}: not set in the file")
        del chain[-1][parts[-1]]
        # An emptied [table] is noise; drop it (and emptied parents) like git config does.
        for depth in range(len(chain) - 1, 0, -1):
            if len(chain[depth]) == 0:
                del chain[depth - 1][parts[depth - 1]]
    return _check_and_write(path, document)


def create_config(path: Path, text: str) -> None:
    """Write ``text`` as a new settings file; :class:`ConfigError` if one exists already."""
    parse_config(text, path)
    try:
        create_atomically(_target(path), text.encode("utf-8"))
    except FileExistsError:
        raise ConfigError(f"{path}: exists already; not overwritten") from None
    except OSError as error:
        raise ConfigError(f"{path}: cannot write: {error}") from None


def _key_parts(path: Path, key: str) -> list[str]:
    parts = key.split(".")
    if not all(part.strip() for part in parts):
        raise ConfigError(f"{path}: {key}: expected a dotted key like site.latitude")
    return parts


def _read_document(path: Path) -> tomlkit.TOMLDocument:
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return tomlkit.parse(NEW_FILE_HEADER)
    except (OSError, UnicodeDecodeError) as error:
        raise ConfigError(f"{path}: cannot read: {error}") from None
    try:
        return tomlkit.parse(text)
    except tomlkit.exceptions.ParseError as error:
        raise ConfigError(f"{path}: not valid TOML ({error}); fix it by hand first") from None


def _check_and_write(path: Path, document: tomlkit.TOMLDocument) -> str:
    text = tomlkit.dumps(document)
    if not text.endswith("\n"):
        text += "\n"  # a value appended to the last line's table ends without one
    parse_config(text, path)  # never write a file that would not load
    try:
        write_atomically(_target(path), text.encode("utf-8"))
    except OSError as error:
        raise ConfigError(f"{path}: cannot write: {error}") from None
    return text


def _target(path: Path) -> Path:
    # A settings file that is a symlink (dotfile managers) is edited where it points, not
    # replaced by a regular file.
    return path.resolve() if path.is_symlink() else path
