"""The error of a bad user input, shared by every reader (re-exported by
:mod:`seatrack.io.table`, where readers import it from).

Kept in its own module so that the modules :mod:`seatrack.io.table` itself uses (the work
budget, compressed inputs) can raise it without importing the table reader.
"""

from __future__ import annotations

__all__ = ["InputError"]


class InputError(ValueError):
    """A user-supplied file or value is malformed. The message names the file, row and problem."""
