"""The CLI's one user-facing error type, and the exit status of a violated requirement (a
leaf module, so commands need no lazy import)."""


class CLIError(Exception):
    """A user-facing error: printed as one line, exit status 2."""


#: exit status of ``optimize`` when the reference re-check violates a requirement.
EXIT_REQUIREMENT_VIOLATED = 3
