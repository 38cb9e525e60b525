"""The option checks of the commands: :mod:`seatrack.api.options` (shared with the API)."""

from seatrack.api.options import IMAGE_SUFFIXES
from seatrack.api.options import option_in
from seatrack.api.options import option_positive
from seatrack.api.options import prepare_outputs

__all__ = ["IMAGE_SUFFIXES", "option_in", "option_positive", "prepare_outputs"]
