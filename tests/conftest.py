"""Fixtures shared by several test files."""
import pytest

from whipple_kick.scenario import Scenario
from whipple_kick.simulation import run


@pytest.fixture(scope="session")
def base():
    """The main job's run: 400 kPa, 635 N, thesis defaults (``simulate --pressure 400 --fz 635``)."""
    return run(Scenario(pressure_kpa=400.0, fz_n=635.0))
