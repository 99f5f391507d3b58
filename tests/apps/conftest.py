"""The fixtures the commands' tests share with the libraries' tests they grew out of."""

from tests.calibration.conftest import omni4
from tests.logs.conftest import recorded

__all__ = ["omni4", "recorded"]
