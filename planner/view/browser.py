"""Opening a view page in headless Chromium (selenium + chromedriver) for checks and timing.

Needs Debian's ``chromium`` and ``chromium-driver`` (or any Chrome with a matching
chromedriver on ``PATH``) and the ``selenium`` package (``dev`` extra). WebGL runs on the
SwiftShader software renderer, so no GPU is needed.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from planner.errors import PlannerError

__all__ = ["BrowserRun", "find_browser", "open_page"]

FLAGS = ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--hide-scrollbars")
_BINARIES = ("chromium", "chromium-browser", "google-chrome")


@dataclass
class BrowserRun:
    """What a page did: ``png`` screenshot bytes (``width`` x ``height`` CSS pixels),
    ``state`` (the page's ``window.viewState``), ``console`` (messages at level SEVERE),
    ``seconds`` from navigation to the page's ready flag, as seen by the driver."""

    png: bytes
    state: dict
    console: list[str]
    seconds: float
    width: int
    height: int


def find_browser() -> tuple[str, str] | str:
    """(chromium, chromedriver) paths, or a one-line reason why none can run."""
    try:
        import selenium  # noqa: F401
    except ImportError:
        return "needs selenium: pip install 'lattice-planner[dev]'"
    browser = next((b for b in map(shutil.which, _BINARIES) if b), None)
    driver = shutil.which("chromedriver")
    if browser is None or driver is None:
        return "needs chromium and chromedriver on PATH (Debian: apt-get install chromium " \
               "chromium-driver)"
    return browser, driver


def open_page(html: str | os.PathLike, *, width: int = 1200, height: int = 800,
              timeout: float = 120.0) -> BrowserRun:
    """Open ``html`` headless, wait for its ready flag, take a screenshot."""
    found = find_browser()
    if isinstance(found, str):
        raise PlannerError(found)
    from selenium import webdriver
    from selenium.common.exceptions import TimeoutException
    from selenium.webdriver.chrome.service import Service
    from selenium.webdriver.support.ui import WebDriverWait

    browser, driver_path = found
    opts = webdriver.ChromeOptions()
    opts.binary_location = browser
    with tempfile.TemporaryDirectory(prefix="planner-chromium.") as profile:
        for f in FLAGS + (f"--user-data-dir={profile}", f"--window-size={width},{height}"):
            opts.add_argument(f)
        opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
        drv = webdriver.Chrome(service=Service(executable_path=driver_path), options=opts)
        try:
            drv.set_window_size(width, height)
            t0 = time.perf_counter()
            drv.get(Path(html).absolute().as_uri())
            try:
                WebDriverWait(drv, timeout, poll_frequency=0.05).until(
                    lambda d: d.execute_script("return !!(window.viewState && "
                                               "window.viewState.ready)"))
            except TimeoutException:
                raise PlannerError(f"{html}: the page did not render within {timeout:g} s") \
                    from None
            seconds = time.perf_counter() - t0
            state = drv.execute_script(
                "const s = window.viewState; return {errors: s.errors, readyMs: s.readyMs, "
                "paths: s.paths.map(p => ({label: p.label, colour: p.colour, screen: p.screen})),"
                " width: window.innerWidth, height: window.innerHeight};")
            png = drv.get_screenshot_as_png()
            console = [e["message"] for e in drv.get_log("browser") if e["level"] == "SEVERE"]
        finally:
            drv.quit()
    return BrowserRun(png, state, console, seconds, state["width"], state["height"])
