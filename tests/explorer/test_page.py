"""The explorer's page in a real browser (headless Chromium, Selenium): what a user does, end to end.

One test, one server and one browser, so that the suite pays for them once (about 15 s on 2 cores): an
out-of-range pressure gets the command line's one-line message beside the field; a run at 300 kPa and
701 N shows its figure and its recovery time; a second run is overlaid on it; the first run's folder,
downloaded by the browser, loads with ``Result.load`` and holds the recovery time the page showed.
"""
import re
import time
import zipfile

import pytest

from tests.conftest import run_console
from whipple_kick import cli
from whipple_kick.explorer.headless import image_shown, set_field, wait
from whipple_kick.simulate.results import Result

pytestmark = pytest.mark.browser

def test_run_overlay_download_and_error(browser, server, capsys):   # no browser: skipped before the server starts
    driver = browser
    driver.get(server)
    assert driver.title == "whipple_kick kick explorer"

    # An out-of-range pressure: the message simulate gives, one line, beside the pressure field; no run.
    status, _, err = run_console(cli.simulate_main, ["--pressure", "1000", "--no-plot"], capsys)
    assert status == 2 and err.count("\n") == 1
    set_field(driver, "pressure_kpa", "1000")
    driver.find_element("id", "run").click()
    error = wait(driver, lambda d: d.find_element("id", "error-pressure_kpa").text)
    assert err == f"error: {error}\n"
    assert "1000" in error and "[300, 500] kPa" in error
    assert driver.find_elements("css selector", "#runs li") == []

    # A run at 300 kPa and 701 N: its figure and its recovery time appear.
    set_field(driver, "pressure_kpa", "300")
    set_field(driver, "fz_n", "701")
    driver.find_element("id", "run").click()
    wait(driver, lambda d: image_shown(d, "figure"))
    assert driver.find_element("id", "error-pressure_kpa").text == ""
    first = driver.find_element("css selector", "#summary li").text
    recovery = re.match(r"Recovered (\d+\.\d{3}) s after the kick", first)
    assert recovery, first

    # A second run (500 kPa): the two are overlaid.
    set_field(driver, "pressure_kpa", "500")
    driver.find_element("id", "run").click()
    wait(driver, lambda d: len(d.find_elements("css selector", "#runs li")) == 2)
    wait(driver, lambda d: image_shown(d, "overlay"))
    boxes = driver.find_elements("css selector", ".overlay-choice")
    assert [b.is_selected() for b in boxes] == [True, True]
    assert [li.text[:3] for li in driver.find_elements("css selector", "#runs li")] == ["1: ", "2: "]

    # The first run's folder, downloaded by the browser: the files simulate writes, read by Result.load.
    driver.find_elements("css selector", "a.download")[0].click()
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        done = [p for p in driver.downloads.iterdir() if p.suffix == ".zip"]
        if done:
            break
        time.sleep(0.1)
    assert done, list(driver.downloads.iterdir())
    with zipfile.ZipFile(done[0]) as archive:
        archive.extractall(driver.downloads / "unzipped")
    (folder,) = (driver.downloads / "unzipped").iterdir()
    assert {p.name for p in folder.iterdir()} == {"trajectory.csv", "summary.json", "scenario.toml", "response.png"}
    result = Result.load(folder)
    assert result.scenario.pressures == (300.0, 300.0) and result.scenario.fz_n == 701.0
    assert f"{result.summary['recovery']['time_s']:.3f}" == recovery[1]

