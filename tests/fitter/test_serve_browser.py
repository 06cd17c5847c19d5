"""`fitter serve` in a real headless browser (Debian's chromium, driven through the
DevTools protocol): a camera calibrated from the demo's board photos, the demo's photos
uploaded on a phone-sized page, each checked, the fit waited for, and the measurements
read off the report page. Skipped without chromium.

With BODYFIT_SCREENSHOTS=DIR it also writes each page's screenshot into DIR (the ones in
docs/serve/ are made so: ``BODYFIT_SCREENSHOTS=docs/serve python -m pytest
tests/fitter/test_serve_browser.py``).
"""

import base64
import json
import os
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import pytest

from bodyfit.fitter.demo.example import write_scene

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="no chromium (apt install chromium)")
PHONE = {"width": 390, "height": 844, "deviceScaleFactor": 2, "mobile": True}
DESKTOP = {"width": 1100, "height": 700, "deviceScaleFactor": 1, "mobile": False}


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _wait_for(check, seconds: float, what: str):
    end = time.time() + seconds
    while time.time() < end:
        value = check()
        if value:
            return value
        time.sleep(0.3)
    raise AssertionError(f"waited {seconds:.0f} s for {what}")


def _answers(url: str) -> bool:
    try:
        urllib.request.urlopen(url, timeout=2)
        return True
    except OSError:
        return False


class Browser:
    """One tab of a headless chromium, commanded over the DevTools protocol."""

    def __init__(self, profile: Path):
        import websocket

        port = _free_port()
        self.process = subprocess.Popen(
            [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
             f"--remote-debugging-port={port}", f"--user-data-dir={profile}", "about:blank"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        targets = _wait_for(lambda: _answers(f"http://127.0.0.1:{port}/json") and json.loads(
            urllib.request.urlopen(f"http://127.0.0.1:{port}/json").read()), 30, "chromium")
        page = next(t for t in targets if t["type"] == "page")
        self.socket = websocket.create_connection(page["webSocketDebuggerUrl"], timeout=60,
                                                 suppress_origin=True)
        self.next_id = 0

    def send(self, method: str, **params) -> dict:
        self.next_id += 1
        self.socket.send(json.dumps({"id": self.next_id, "method": method, "params": params}))
        while True:
            message = json.loads(self.socket.recv())
            if message.get("id") == self.next_id:
                assert "error" not in message, message
                return message["result"]

    def evaluate(self, expression: str):
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True,
                           awaitPromise=True)
        assert "exceptionDetails" not in result, result
        return result["result"].get("value")

    def open(self, url: str, metrics: dict) -> None:
        self.send("Emulation.setDeviceMetricsOverride", **metrics)
        self.send("Page.navigate", url=url)
        _wait_for(lambda: self.evaluate("document.readyState") == "complete", 30, url)

    def upload(self, selector: str, *paths: Path) -> None:
        root = self.send("DOM.getDocument")["root"]["nodeId"]
        node = self.send("DOM.querySelector", nodeId=root, selector=selector)["nodeId"]
        self.send("DOM.setFileInputFiles", nodeId=node, files=[str(p) for p in paths])

    def screenshot(self, name: str) -> None:
        folder = os.environ.get("BODYFIT_SCREENSHOTS")
        if folder:
            Path(folder).mkdir(parents=True, exist_ok=True)
            shot = self.send("Page.captureScreenshot", format="png", captureBeyondViewport=True)
            (Path(folder) / f"{name}.png").write_bytes(base64.b64decode(shot["data"]))

    def close(self) -> None:
        self.socket.close()
        self.process.kill()
        self.process.wait()


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    """`fitter serve` on a free port of this machine, with one worker."""
    data = tmp_path_factory.mktemp("studio")
    port = _free_port()
    server = subprocess.Popen([sys.executable, "-m", "bodyfit.fitter.cli.main", "-q", "serve",
                               "--port", str(port), "--data", str(data), "--workers", "1"])
    url = f"http://127.0.0.1:{port}"
    try:
        _wait_for(lambda: _answers(url), 60, "fitter serve")
        yield url, data
    finally:
        server.terminate()
        server.wait(30)


@pytest.fixture()
def browser(tmp_path):
    browser = Browser(tmp_path / "profile")
    yield browser
    browser.close()


def test_calibrate_then_measure_a_person_on_a_phone_page(served, browser, body_model,
                                                        tmp_path):
    url, data = served
    scene = write_scene(body_model, tmp_path / "demo")
    browser.open(url + "/cameras", DESKTOP)
    browser.evaluate("""(() => {
        const form = document.getElementById('calibrate');
        form.name.value = 'studio phone'; form.board.value = '%s'; form.square_mm.value = '%g';
    })()""" % (scene.settings.board, scene.settings.square_mm))
    browser.upload("input[name=photos]", *scene.board_photos)
    browser.evaluate("document.querySelector('#calibrate button').click()")
    result = _wait_for(lambda: "registered" in browser.evaluate(
        "document.getElementById('result').innerText") and browser.evaluate(
        "document.getElementById('result').innerText"), 120, "the calibration")
    assert result.startswith(f"registered studio phone: {len(scene.board_photos) - 2} used")
    assert "bent.png: outlier" in result and "blurred.png: too blurry" in result
    browser.screenshot("cameras")

    browser.open(url + "/", PHONE)
    browser.evaluate("""(() => {
        const form = document.getElementById('measure');
        form.person.value = 'Ann Example'; form.height_cm.value = '%s';
        form.sex.value = 'unknown'; form.camera.value = '1';
    })()""" % f"{scene.truth['O'] / 10:.1f}")
    for view in ("front", "side"):
        browser.upload(f"#{view}-file", getattr(scene, view))
    _wait_for(lambda: not browser.evaluate("document.getElementById('go').disabled"), 60,
              "both photos to pass the check")
    verdicts = browser.evaluate("document.getElementById('front-verdict').innerText")
    assert verdicts.startswith("passes the check: the front photo")
    browser.screenshot("measure")
    browser.evaluate("document.getElementById('go').click()")
    _wait_for(lambda: "/fits/" in browser.evaluate("location.href"), 30, "the fit's page")
    fit_url = browser.evaluate("location.href")
    browser.screenshot("fit-progress")
    _wait_for(lambda: browser.evaluate("document.querySelectorAll('[data-measurement]').length"),
              300, "the fit")
    shown = browser.evaluate("""Object.fromEntries([...document.querySelectorAll(
        '[data-measurement]')].map(cell => [cell.dataset.measurement, cell.innerText]))""")
    assert "Camera: studio phone (calibrated)" in browser.evaluate("document.body.innerText")
    fit_id = fit_url.rstrip("/").rsplit("/", 1)[1]
    stored = json.loads((data / "fits" / fit_id / "result" / "measurements.json").read_text())
    assert {k: float(v) for k, v in shown.items()} == {
        k: round(v["value_mm"] / 10, 1) for k, v in stored["measurements"].items()}
    browser.open(fit_url, DESKTOP)
    browser.screenshot("report")
    browser.open(url + "/people?q=ann", DESKTOP)
    assert "Ann Example" in browser.evaluate("document.body.innerText")
    browser.screenshot("people")
    browser.open(url + "/people/Ann%20Example", DESKTOP)
    assert "shoulder to crotch length" in browser.evaluate("document.body.innerText")
    browser.screenshot("person")
