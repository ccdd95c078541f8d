"""The scopelink command line."""

from __future__ import annotations


def entry() -> int:
    """The ``scopelink`` program: :func:`scopelink.cli.main.main`, with Ctrl-C during the
    imports (the first fraction of a second of any command) ending quietly like Ctrl-C later."""
    try:
        from scopelink.cli.main import main  # noqa: PLC0415 - Ctrl-C may land during imports

        return main()
    except KeyboardInterrupt:
        return 130
