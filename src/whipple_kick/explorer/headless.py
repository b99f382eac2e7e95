"""The explorer started as its console script starts it, and the system's headless Chromium driven by Selenium.

One place for what the browser tests (tests/explorer), the benchmark (scripts/bench_explorer.py) and the
documentation's screenshots (docs/explorer.md) do alike. The browser is the system's (Debian: ``apt-get
install -y chromium chromium-driver`` gives /usr/bin/chromium and /usr/bin/chromedriver;
``WHIPPLE_KICK_CHROMIUM`` and ``WHIPPLE_KICK_CHROMEDRIVER`` name others): nothing is downloaded, and
Selenium (the test extra) is told where both are, so it never looks for them on the internet.
"""
import os
import pathlib
import re
import select
import shutil
import subprocess
import sys
import time

#: Seconds the server may take to print its address: a cold cache builds the compiled model first (~25-60 s).
START_TIMEOUT_S = 300.0
#: The browser's window [px]: the form and the figure side by side.
WINDOW = (1400, 1100)


class NotStarted(RuntimeError):
    """The explorer did not print its address (its output says why)."""


def start_server(*args, timeout=START_TIMEOUT_S):
    """``whipple-kick-explorer --port 0 *args`` in a new process (this Python): ``(process, address)``.

    End it with ``process.terminate()`` (SIGTERM: one line, exit status 143, its pool ended).
    """
    proc = subprocess.Popen([sys.executable, "-c", "from whipple_kick.explorer.server import main; main()",
                             "--port", "0", *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True)
    seen, deadline = [], time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        ready, _, _ = select.select([proc.stdout], [], [], 1.0)
        if ready:
            line = proc.stdout.readline()
            seen.append(line)
            found = re.search(r"serving on (http://127\.0\.0\.1:\d+/)", line)
            if found:
                return proc, found[1]
    proc.kill()
    proc.wait()
    raise NotStarted(f"the explorer did not start: {''.join(seen)[-2000:]}")


def stop_server(proc, timeout=30.0):
    """SIGTERM, then SIGKILL after ``timeout`` seconds."""
    proc.terminate()
    try:
        proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def _program(names, variable):
    """The program named by ``variable``, else the first of ``names`` on PATH, else None."""
    given = os.environ.get(variable)
    if given:
        return given if pathlib.Path(given).is_file() else None
    return next((shutil.which(n) for n in names if shutil.which(n)), None)


def missing():
    """Why no headless Chromium can be driven here (a sentence), or None where it can."""
    try:
        import selenium  # noqa: F401 -- only whether it is installed
    except ImportError:
        return "Selenium is not installed (pip install -e '.[test]')"
    if _program(("chromium", "chromium-browser"), "WHIPPLE_KICK_CHROMIUM") is None \
            or _program(("chromedriver",), "WHIPPLE_KICK_CHROMEDRIVER") is None:
        return ("no headless Chromium and its driver on this machine (apt-get install -y chromium chromium-driver; "
                "or set WHIPPLE_KICK_CHROMIUM and WHIPPLE_KICK_CHROMEDRIVER)")
    return None


def chromium(downloads=None, window=WINDOW):
    """A headless Chromium (a Selenium driver) whose downloads go to ``downloads``; :func:`missing` first."""
    from selenium import webdriver

    os.environ.setdefault("SE_OFFLINE", "true")   # Selenium Manager, should it run, looks nothing up online
    options = webdriver.ChromeOptions()
    options.binary_location = _program(("chromium", "chromium-browser"), "WHIPPLE_KICK_CHROMIUM")
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", "--no-first-run",
                "--disable-extensions", f"--window-size={window[0]},{window[1]}"):
        options.add_argument(arg)
    if downloads is not None:
        options.add_experimental_option("prefs", {"download.default_directory": str(downloads),
                                                  "download.prompt_for_download": False})
    service = webdriver.ChromeService(executable_path=_program(("chromedriver",), "WHIPPLE_KICK_CHROMEDRIVER"))
    driver = webdriver.Chrome(options=options, service=service)
    if downloads is not None:
        driver.execute_cdp_cmd("Page.setDownloadBehavior", {"behavior": "allow", "downloadPath": str(downloads)})
    return driver


def set_field(driver, name, value):
    """Type ``value`` into the page's field ``name`` (a text input), replacing what it held."""
    box = driver.find_element("id", f"field-{name}")
    box.clear()
    box.send_keys(str(value))


def image_shown(driver, element_id):
    """Whether the page's image ``element_id`` is displayed and loaded (its natural width is known)."""
    return driver.execute_script(
        "const img = document.getElementById(arguments[0]);"
        "return !img.hidden && img.complete && img.naturalWidth > 0;", element_id)


def wait(driver, condition, timeout=120.0):
    """Poll ``condition(driver)`` every 0.1 s until it is true (returned) or ``timeout`` seconds pass."""
    from selenium.webdriver.support.ui import WebDriverWait

    return WebDriverWait(driver, timeout, poll_frequency=0.1).until(condition)
