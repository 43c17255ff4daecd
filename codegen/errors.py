"""User-facing errors of mpcgen.

Every error a user can cause with bad input derives from :class:`MpcgenError`;
the command line prints ``str(error)`` (one line, no traceback) and exits
non-zero.  :class:`ConfigError` names the file, the dotted field, the
offending value and what would have been allowed, as the spec requires
("a config error names the file, the field, the value and the allowed range").
"""
from __future__ import annotations

__all__ = ["MpcgenError", "ConfigError", "UsageError", "Unsupported", "Marker", "MISSING", "FILE_FIELD"]

#: ``ConfigError.field`` for problems with the file as a whole (missing,
#: unreadable, not TOML).
FILE_FIELD = "(file)"

_MAX_VALUE_CHARS = 120


class Marker:
    """A placeholder value whose ``repr`` is a fixed text (e.g. ``<missing>``).

    Used as ``ConfigError.value`` where there is no offending value to show.
    """

    __slots__ = ("text",)

    def __init__(self, text: str) -> None:
        self.text = text

    def __repr__(self) -> str:
        return self.text


#: The value of a required field or section that is absent.
MISSING = Marker("<missing>")


class MpcgenError(Exception):
    """Base class of every error caused by user input (config, CLI, serial)."""


class ConfigError(MpcgenError):
    """An invalid configuration value.

    Attributes:
        file: the config file as given by the user (or ``(command line)``).
        field: dotted field path, e.g. ``controller.strategy``; ``(file)``
            when the file itself is the problem.
        value: the offending value (:data:`MISSING` when absent).
        allowed: human-readable description of what is allowed.
    """

    def __init__(self, file: str, field: str, value: object, allowed: str) -> None:
        self.file = str(file)
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(self.file, field, value, allowed)

    def __str__(self) -> str:
        text = f"{self.file}: {self.field} = {_show(self.value)}: {self.allowed}"
        return " ".join(text.splitlines())


def _show(value: object) -> str:
    """``repr`` of a value, shortened to one reasonably short line."""
    text = repr(value)
    if len(text) > _MAX_VALUE_CHARS:
        text = text[: _MAX_VALUE_CHARS - 3] + "..."
    return text


class UsageError(MpcgenError):
    """A command-line argument is invalid (exit code 2)."""


class Unsupported(UsageError):
    """The command or option does not apply to the config's topology or strategy (exit code 2)."""
