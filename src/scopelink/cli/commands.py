"""The subcommands, and their parsers filled in only when one is used (docs/cli.md, "Start-up").

``scopelink --help`` needs each command's name and one-line help, nothing more: they are listed
here, in :data:`COMMANDS`, and the module that defines a command (its options, its run function
and everything they import) is imported only when that command is parsed or its help is shown.
A command module offers ``register(commands)``, which fills in each of its commands' parsers
through :meth:`CommandParsers.parser` and sets ``run`` (namespace -> exit status) as their default.
"""

from __future__ import annotations

import argparse
import importlib
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final, NoReturn

__all__ = [
    "COMMANDS",
    "Command",
    "CommandParser",
    "CommandParsers",
    "SuggestingParser",
    "add_commands",
    "did_you_mean",
]


@dataclass(frozen=True, slots=True)
class Command:
    """A subcommand: its name, its line in ``scopelink --help``, and the module that defines it."""

    name: str
    help: str
    module: str
    """Under ``scopelink.cli``; imported only when this command is used."""


COMMANDS: Final = (
    Command(
        "serve",
        "run a mount with its servers (the simulated mount when no device is given)",
        "serve_command",
    ),
    Command("emulate", "run an emulated device on a pty or TCP port", "emulate_command"),
    Command(
        "decode",
        "annotate a byte trace of SynScan or Sky Tracker / Sky Commander traffic",
        "decode_command",
    ),
    Command(
        "record",
        "record a session with a device, every byte with its time (for decode and replay)",
        "record_command",
    ),
    Command("ports", "list serial ports, flagging likely hand-control cables", "ports_command"),
    Command(
        "doctor",
        "try what answers on a port and say what it is and what to do (read-only probes)",
        "doctor_command",
    ),
    Command(
        "info",
        "identify what is on a port: SynScan firmware and model, Sky Tracker, Sky Commander",
        "info_command",
    ),
    Command(
        "status",
        "show RA/Dec, Alt/Az, pier side, slewing and tracking (live with --watch)",
        "status_command",
    ),
    Command(
        "goto",
        "slew to a named object or to coordinates, with progress; Ctrl-C aborts",
        "goto_command",
    ),
    Command("sync", "tell the mount it points at a named object or at coordinates", "goto_command"),
    Command(
        "pointing",
        "list the syncs a running serve keeps on the PC, with residuals; remove one; clear",
        "pointing_command",
    ),
    Command(
        "move",
        "turn one axis at a rate until Ctrl-C (or for --for seconds), then stop it",
        "motion_commands",
    ),
    Command("stop", "stop every motion now (gotos and manual moves)", "motion_commands"),
    Command(
        "track",
        "tracking on, off, or a mode; or follow the Moon, a planet, a comet, a satellite",
        "track_command",
    ),
    Command("park", "move to the park position and stop tracking", "motion_commands"),
    Command("unpark", "allow motion again after park", "motion_commands"),
    Command(
        "guide",
        "one guide pulse: DIRECTION (north/south/east/west) for MS milliseconds",
        "motion_commands",
    ),
    Command(
        "skycommander",
        "the Sky Commander's memory (slots, upload, clear) and a live push-to view",
        "skycommander_command",
    ),
    Command("time", "set the mount's clock from this computer's (UTC)", "setup_commands"),
    Command("site", "send the configured site (or --site) to the mount", "setup_commands"),
    Command("config", "show or change the settings file", "config_command"),
)
"""Every subcommand, in the order ``scopelink --help`` lists them."""


_INVALID_CHOICE: Final = re.compile(r"invalid choice: '([^']*)' \(choose from (.*)\)")


def did_you_mean(word: str, candidates: Iterable[str]) -> str:
    """``"; did you mean X?"`` for the candidate closest to a mistyped ``word``, else ``""``."""
    import difflib  # noqa: PLC0415 - only on a mistake: start-up stays light (docs/cli.md)

    close = difflib.get_close_matches(word, list(candidates), n=1)  # default cutoff, 0.6
    return f"; did you mean {close[0]}?" if close else ""


class SuggestingParser(argparse.ArgumentParser):
    """A parser whose "invalid choice" errors (a mistyped command, action or option value) end
    with the closest valid choice: ``scopelink stauts`` -> "did you mean status?"."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.commands: Mapping[str, SuggestingParser] = {}
        """The subcommands' parsers, by name (the top-level parser's, from add_commands)."""

    def error(self, message: str) -> NoReturn:
        match = _INVALID_CHOICE.search(message)
        if match is not None:
            choices = re.findall(r"'([^']*)'", match[2])
            message += did_you_mean(match[1], choices)
        super().error(message)

    def refuse_unknown_options(self, extras: Sequence[str]) -> NoReturn:
        """Fail on arguments this parser does not take, naming the closest options it does."""
        known = [option for action in _actions_within(self) for option in action.option_strings]
        hints = "".join(
            did_you_mean(extra.partition("=")[0], known) for extra in extras if extra[:1] == "-"
        )
        self.error(f"unrecognized arguments: {' '.join(extras)}{hints}")


def _actions_within(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The parser's actions and those of its nested subcommands (``emulate synscan``...)."""
    actions = list(parser._actions)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for nested in action.choices.values():
                actions.extend(_actions_within(nested))
    return actions


class CommandParser(SuggestingParser):
    """A subcommand's parser, filled in by its module the first time it parses or shows help."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.module = ""
        """The defining module, still to be imported; empty once filled in (or for a parser
        made whole, like ``emulate``'s per-device parsers)."""
        self.siblings: Mapping[str, CommandParser] = {}

    def fill_in(self) -> None:
        """Import this command's module and let it declare the options of all its commands."""
        if not self.module:
            return
        module = importlib.import_module(f"scopelink.cli.{self.module}")
        own = {name: p for name, p in self.siblings.items() if p.module == self.module}
        module.register(CommandParsers(own))
        for parser in own.values():
            parser.module = ""

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self.fill_in()
        return super().parse_known_args(args, namespace)

    # ``*args``: Python 3.15 passes a formatter.
    def format_help(self, *args: Any) -> str:
        self.fill_in()
        return super().format_help(*args)

    def format_usage(self, *args: Any) -> str:
        self.fill_in()
        return super().format_usage(*args)


class CommandParsers:
    """What a command module's ``register`` is given: its commands' parsers, by name."""

    def __init__(self, parsers: Mapping[str, argparse.ArgumentParser]) -> None:
        self._parsers = parsers

    def parser(
        self,
        name: str,
        *,
        description: str,
        epilog: str | None = None,
        formatter_class: type[argparse.HelpFormatter] = argparse.HelpFormatter,
    ) -> argparse.ArgumentParser:
        """The parser of command ``name``, given its description and epilog, to add options to."""
        parser = self._parsers[name]
        parser.description = description
        parser.epilog = epilog
        parser.formatter_class = formatter_class
        return parser


def add_commands(parser: argparse.ArgumentParser) -> Mapping[str, CommandParser]:
    """Add every command of :data:`COMMANDS` to ``parser``, each to be filled in when used;
    returns their parsers by name."""
    subparsers = parser.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=CommandParser
    )
    parsers: dict[str, CommandParser] = {}
    for command in COMMANDS:
        parsers[command.name] = subparsers.add_parser(command.name, help=command.help)
        parsers[command.name].module = command.module
    for each in parsers.values():
        each.siblings = parsers
    return parsers
