"""The error type of every problem the user can fix.

:class:`UserError` is the base of :class:`seatrack.io.table.InputError` (a bad input file
or value), :class:`seatrack.config.ConfigError` (a bad configuration key or value; also a
``ValueError``) and :class:`seatrack.io.atomic.OutputError` (an output that cannot be
written; also an ``OSError``). The command line prints such an error as one
``error: ...`` line and exits with status 2; any other exception is a bug in seatrack.
"""

from __future__ import annotations

__all__ = ["UserError", "InputError"]


class UserError(Exception):
    """A problem in the user's input, configuration or output path; the message says which
    file, line, key or option and what is wrong."""


class InputError(UserError, ValueError):
    """A user-supplied file or value is malformed. The message names the file, row and problem."""
