"""The one error type subcommands raise to fail with a clear line instead of a traceback."""


class CommandError(Exception):
    """A failure to report as one clear line, with an optional hint on what to do."""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.hint = hint
