"""Debian's Chromium for the browser tests: where it is, how it starts (no network, WebGL on
SwiftShader) and a Playwright browser per test module (``browser_for``)."""
from __future__ import annotations

import contextlib
import os
import re
import shutil

import pytest

ARGS = ["--no-sandbox", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run", "--disable-quic",
        # WebGL on SwiftShader, said explicitly: Chromium may stop falling back to it silently
        "--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
#: Console messages of the GL stack, not of the page.
BENIGN = re.compile(r"GL Driver Message|GPU stall")


def chromium() -> str:
    """Chromium's path, or a skip that says how CI installs it."""
    for name in (os.environ.get("CHROMIUM", ""), "chromium", "chromium-browser", "google-chrome"):
        if name and shutil.which(name):
            return shutil.which(name)
    pytest.skip("no Chromium installed (.ci/run installs Debian's chromium)")


@contextlib.contextmanager
def browser_for():
    """A Playwright Chromium (skips where Chromium or Playwright is missing)."""
    exe = chromium()
    sync_api = pytest.importorskip("playwright.sync_api", reason="Playwright for Python not installed")
    with sync_api.sync_playwright() as p:
        b = p.chromium.launch(executable_path=exe, args=ARGS)
        try:
            yield b
        finally:
            b.close()
