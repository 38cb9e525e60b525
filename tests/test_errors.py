"""seatrack.errors: one InputError for every reader, a user error (exit status 2)."""

from seatrack import errors
from seatrack.io import table


def test_one_class_for_every_reader():
    assert table.InputError is errors.InputError
    assert issubclass(errors.InputError, errors.UserError)
    assert issubclass(errors.InputError, ValueError)
