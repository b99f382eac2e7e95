"""The explorer's server, started as its console script starts it, and the system's headless Chromium.

Both from :mod:`whipple_kick.explorer.headless`. Without Tornado, Selenium, a browser or its driver the tests
that need them skip with the reason; nothing is downloaded.
"""
import pathlib

import pytest

STUDY = pathlib.Path(__file__).resolve().parents[2] / "docs" / "uncertainty_study"
#: The page's stability sweep in the tests: four speeds (the default 191 take about 9 s).
STABILITY_SPEEDS = "2:5:1"


class Address(str):
    """The server's address, and its process id (``pid``)."""

    __slots__ = ("pid",)

    def __new__(cls, url, pid):
        self = super().__new__(cls, url)
        self.pid = pid
        return self


@pytest.fixture(scope="package")
def server(tmp_path_factory):
    """``whipple-kick-explorer --port 0 --study docs/uncertainty_study --workers 2 --speeds 2:5:1``: its address
    and process id (one server for the package's tests in a test process)."""
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
