"""The CLI's one user-facing error type (a leaf module, so commands need no lazy import)."""


class CLIError(Exception):
    """A user-facing error: printed as one line, exit status 2."""
