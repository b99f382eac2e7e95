"""Fixtures shared by several test files."""
from collections.abc import Sequence
import dataclasses
import pathlib

import pytest

import whipple_kick as wk
from whipple_kick.simulate.scenario import Scenario
from whipple_kick.simulate.simulation import run


@pytest.fixture(scope="session")
def base():
    """The main job's run: 400 kPa, 635 N, thesis defaults (``simulate --pressure 400 --fz 635``)."""
    return run(Scenario(pressure_kpa=400.0, fz_n=635.0))


# The bicycle with a rider for 635 N at the rear, its LQR rider at 3 m/s and T03 at 400 kPa: the slip
# model's own tests and the call-path tests build their model from these.
@pytest.fixture(scope="module")
def rider_bike():
    bike = wk.bicycles.load("balanceassist_v1")
    combined, _ = wk.riders.for_rear_load(bike, fz_n=635.0)
    return combined


@pytest.fixture(scope="module")
def gains(rider_bike):
    K, _ = wk.control.lqr_gains(rider_bike, 3.0)
    return wk.control.gains_dict(K)


@pytest.fixture(scope="module")
def t03():
    return wk.tyres.load("T03", pressure_kpa=400)


# Sweeps: short runs, since the sweep machinery, not the physics, is under test there.
SWEEP_BASE = Scenario(duration=3.0, settle=0.1, output_rate=200.0, fz_n=635.0)
# 600 kPa is outside T03's measured 300-500 kPa: that case fails with an InputError.
SWEEP_GRID = {"pressure_kpa": [300, 400, 500, 600]}


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    """A four-case pressure sweep in its own folder (one case fails): ``(folder, table)``."""
    folder = tmp_path_factory.mktemp("sweep") / "grid"
    table = wk.sweep(SWEEP_GRID, base=SWEEP_BASE, folder=folder, progress=False)
    return folder, table


def run_console(main, argv, capsys):
    """Run a console script's ``main(argv)`` in-process; return (status, stdout, stderr)."""
    with pytest.raises(SystemExit) as info:
        main(argv)
    out, err = capsys.readouterr()
    return info.value.code, out, err


@pytest.fixture(scope="session")
def dask_client():
    """One Dask cluster of two worker processes for the whole session (each start took 3-4 s)."""
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(processes=True, n_workers=2, threads_per_worker=1,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        yield client


#: Every :class:`Scenario` field's default.
SCENARIO_DEFAULTS = {f.name: f.default for f in dataclasses.fields(Scenario)}


def other_value(name, other_rider):
    """A valid value of :class:`Scenario` field ``name`` other than its default (switches: another choice).

    ``other_rider`` is the value for ``rider`` (a Yeadon rider file other than the default).
    """
    default = SCENARIO_DEFAULTS[name]
    special = {"bicycle": "browser_with_rider", "rider": other_rider, "tyre": "T04", "coefficient_set": "chapter8",
               "friction": "plate", "fz_n": 701.0, "rider_mass_kg": 80.0, "rear_load_share": 0.66, "pressure_front_kpa": 350.0,
               "pressure_rear_kpa": 350.0, "design_speed": 4.0, "thesis_load_n": 701.0, "kick_duration": 0.2,
               "kick_accel": 10.0, "kick_table": "plate.csv", "steer_limit_deg": 80.0, "settle": 0.3,
               "reflex_delay": 0.05, "arm_stiffness": 5.0, "arm_damping": 2.0, "carcass_damping": 50.0,
               "reflex_roll": -3.0, "reflex_roll_rate": -1.0, "reflex_steer": 2.0, "reflex_steer_rate": 0.5}
    if name in special:
        return special[name]
    if isinstance(default, bool):
        return not default
    if isinstance(default, str):
        choices = _choices(name)
        return next(c for c in choices if c != default)
    return default * 0.8


def _choices(name):
    from whipple_kick.library import inputs
    from whipple_kick.simulate import scenario as module
    for label in dir(module):
        value = getattr(module, label)
        if label.isupper() and isinstance(value, Sequence) and not isinstance(value, str) \
                and SCENARIO_DEFAULTS[name] in value and len(value) > 1 and all(isinstance(v, str) for v in value):
            return tuple(value)   # a tuple, or a listing read when asked (the declared tyre forms)
    if name == "kick_profile":
        return inputs.PROFILES
    if name == "kick_direction":
        return inputs.DIRECTIONS
    if name == "carcass_sliding":
        from whipple_kick.model import carcass
        return carcass.SLIDING_LAWS
    raise AssertionError(f"no choices known for field {name!r}")


# ------------------------------------------------------------------ the explorer (tests/explorer)
# Here, not in tests/explorer/conftest.py: two conftest.py in folders without __init__.py are both the module
# "conftest", and the second one imported hid this one's helpers from the tests that import them.
STUDY = pathlib.Path(__file__).resolve().parents[1] / "docs" / "uncertainty_study"
#: The page's stability sweep in the tests: four speeds (the default 191 take about 9 s).
STABILITY_SPEEDS = "2:5:1"


class Address(str):
    """The server's address, and its process id (``pid``)."""

    __slots__ = ("pid",)

    def __new__(cls, url, pid):
        self = super().__new__(cls, url)
        self.pid = pid
        return self


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    """``whipple-kick-explorer --port 0 --study docs/uncertainty_study --workers 2 --speeds 2:5:1``: its address
    and process id (one server per test process)."""
    pytest.importorskip("tornado", reason="the explorer's server needs Tornado: pip install -e '.[app]'")
    from whipple_kick.explorer import headless

    proc, url = headless.start_server("--study", STUDY, "--workers", 2, "--speeds", STABILITY_SPEEDS,
                                      "--workdir", tmp_path_factory.mktemp("explorer_runs"))
    yield Address(url, proc.pid)
    headless.stop_server(proc)


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    """A headless Chromium (Selenium) whose downloads go to its own folder (``browser.downloads``)."""
    from whipple_kick.explorer import headless

    why = headless.missing()
    if why is not None:
        pytest.skip(why)
    downloads = tmp_path_factory.mktemp("downloads")
    driver = headless.chromium(downloads)
    driver.downloads = downloads
    yield driver
    driver.quit()
