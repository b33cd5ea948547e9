"""Headless Chromium for the tests of the HTML pages (report.html, the plan viewer), driven by
Selenium through Debian's chromedriver.

Chromium and chromedriver come from Debian's ``chromium`` and ``chromium-driver`` packages
(``make test`` installs them where it runs as root with apt; :func:`browser` skips naming what is
missing elsewhere, or fails where ``TT_REQUIRE_BROWSER=1`` says the set-up installed them). The flags
are those that work on a closed network: no background connections, no component updates, a fresh
profile folder. Console messages of level SEVERE (errors) are collected per page.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

CHROMIUM = os.environ.get("TT_CHROMIUM", "/usr/bin/chromium")
CHROMEDRIVER = os.environ.get("TT_CHROMEDRIVER", "/usr/bin/chromedriver")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--window-size=1400,1000")


def _missing() -> str:
    """Why no browser test can run here, or ``""``."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "selenium is not installed (pip install -e \".[test]\")"
    for path, package in ((CHROMIUM, "chromium"), (CHROMEDRIVER, "chromium-driver")):
        if not (Path(path).is_file() and os.access(path, os.X_OK)):
            return f"no {path} (Debian's {package} package: apt-get install -y chromium chromium-driver)"
    return ""


@contextmanager
def browser() -> Iterator[Any]:
    """A headless Chromium (a Selenium WebDriver), closed with its profile folder at the end; skips
    the test with the reason when there is none (fails instead under ``TT_REQUIRE_BROWSER=1``)."""
    why = _missing()
    if why:
        if os.environ.get("TT_REQUIRE_BROWSER") == "1":
            pytest.fail(f"TT_REQUIRE_BROWSER=1 but {why}")
        pytest.skip(f"no headless browser: {why}")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    profile = tempfile.mkdtemp(prefix="tt-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for f in (*FLAGS, f"--user-data-dir={profile}"):
        opts.add_argument(f)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver = webdriver.Chrome(options=opts, service=Service(executable_path=CHROMEDRIVER))
    try:
        yield driver
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)


def open_page(driver: Any, path: Path, ready: str, timeout: float = 20.0) -> None:
    """Load the file ``path`` and wait until the JavaScript expression ``ready`` is true."""
    from selenium.webdriver.support.ui import WebDriverWait

    driver.get(path.resolve().as_uri())
    WebDriverWait(driver, timeout, poll_frequency=0.05).until(lambda d: d.execute_script(f"return !!({ready});"))


def console_errors(driver: Any) -> list[str]:
    """The console's error messages since the last call (level SEVERE)."""
    return [e["message"] for e in driver.get_log("browser") if e.get("level") == "SEVERE"]
