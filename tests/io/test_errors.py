"""InputError (seatrack.io.errors): one class, re-exported by seatrack.io.table, and a
user error for the command line (a ValueError: exit status 2)."""

from seatrack.io import errors
from seatrack.io import table


def test_one_class_for_every_reader():
    assert table.InputError is errors.InputError
    assert issubclass(errors.InputError, ValueError)
