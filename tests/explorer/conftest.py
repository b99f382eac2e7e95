"""The explorer's server, started as its console script starts it, and a headless Chromium driven by Selenium.

The browser is the system's (Debian: ``apt-get install -y chromium chromium-driver`` gives /usr/bin/chromium and
/usr/bin/chromedriver; ``WHIPPLE_KICK_CHROMIUM`` and ``WHIPPLE_KICK_CHROMEDRIVER`` name others): nothing is
downloaded. Without Selenium, Tornado, a browser or its driver the tests that need them skip with the reason.
"""
import os
import pathlib
import re
import select
import shutil
import subprocess
import sys
import time

import pytest

#: Seconds the server may take to print its address: a cold cache builds the compiled model first (~25-60 s).
START_TIMEOUT_S = 300.0
STUDY = pathlib.Path(__file__).resolve().parents[2] / "docs" / "uncertainty_study"


def _first(names, variable):
    """The program named by ``variable``, else the first of ``names`` on PATH, else None."""
    given = os.environ.get(variable)
    if given:
        return given if pathlib.Path(given).is_file() else None
    return next((shutil.which(n) for n in names if shutil.which(n)), None)


@pytest.fixture(scope="package")
def server(tmp_path_factory):
    """``whipple-kick-explorer --port 0 --study docs/uncertainty_study --workers 2``: its address (one server for
    the package's tests in a test process)."""
    pytest.importorskip("tornado", reason="the explorer's server needs Tornado: pip install -e '.[app]'")
    workdir = tmp_path_factory.mktemp("explorer_runs")
    proc = subprocess.Popen(
        [sys.executable, "-c", "from whipple_kick.explorer.server import main; main()", "--port", "0",
         "--study", str(STUDY), "--workers", "2", "--workdir", str(workdir)],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    url, seen, deadline = None, [], time.monotonic() + START_TIMEOUT_S
    while url is None and time.monotonic() < deadline and proc.poll() is None:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            line = proc.stdout.readline()
            seen.append(line)
            found = re.search(r"serving on (http://127\.0\.0\.1:\d+/)", line)
            url = found[1] if found else None
    if url is None:
        proc.kill()
        pytest.fail(f"the explorer did not start: {''.join(seen)[-2000:]}")
    yield url
    proc.terminate()   # SIGTERM: one line, exit status 143, its pool ended
    try:
        proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


@pytest.fixture(scope="module")
def browser(tmp_path_factory):
    """A headless Chromium (Selenium) whose downloads go to its own folder (``browser.downloads``)."""
    webdriver = pytest.importorskip("selenium.webdriver", reason="the browser tests need Selenium (the test extra)")
    chromium = _first(("chromium", "chromium-browser"), "WHIPPLE_KICK_CHROMIUM")
    driver_path = _first(("chromedriver",), "WHIPPLE_KICK_CHROMEDRIVER")
    if chromium is None or driver_path is None:
        pytest.skip("no headless Chromium and its driver on this machine (apt-get install -y chromium "
                    "chromium-driver; or set WHIPPLE_KICK_CHROMIUM and WHIPPLE_KICK_CHROMEDRIVER)")
    downloads = tmp_path_factory.mktemp("downloads")
    options = webdriver.ChromeOptions()
    options.binary_location = chromium
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--window-size=1400,1100", "--no-first-run", "--disable-extensions"):
        options.add_argument(arg)
    options.add_experimental_option("prefs", {"download.default_directory": str(downloads),
                                              "download.prompt_for_download": False})
    driver = webdriver.Chrome(options=options, service=webdriver.ChromeService(executable_path=driver_path))
    driver.execute_cdp_cmd("Page.setDownloadBehavior", {"behavior": "allow", "downloadPath": str(downloads)})
    driver.downloads = downloads
    yield driver
    driver.quit()
