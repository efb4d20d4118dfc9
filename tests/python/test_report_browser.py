"""The HTML report in headless Chromium, driven over the DevTools protocol (a pipe, no port):
it loads from a file URL with no console error or exception, every picture is decoded and
shows something (pixel statistics of a screenshot of it), and the table sorts.

Run by CTest with the environment of test_visproxy.py. Chromium (Debian's `chromium`) and
Pillow (`python3-pil`) are installed by `cmake/bootstrap.sh test`.
"""

import base64
import io
import json
import os
import pathlib
import shutil
import subprocess
import tempfile

import pytest

PIL = pytest.importorskip("PIL.Image")

CLI = os.environ.get("VISPROXY_CLI", "visproxy")
MESHES = pathlib.Path(os.environ["VISPROXY_MESH_DIR"]).resolve()
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
PROXIES = ["aabb", "hull:32", "quadric:256", "spheres:25", "inside:8"]


class DevTools:
    """Chromium started with --remote-debugging-pipe: commands on its fd 3, replies and
    events on its fd 4, each a JSON message ended by a NUL byte."""

    def __init__(self, profile):
        to_browser_read, self._to_browser = os.pipe()
        self._from_browser, from_browser_write = os.pipe()
        flags = ["--headless", "--no-sandbox", "--disable-gpu", "--remote-debugging-pipe", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-quic",
                 "--hide-scrollbars", f"--user-data-dir={profile}", "about:blank"]
        self.process = subprocess.Popen(
            ["bash", "-c", f'exec "$0" "$@" 3<&{to_browser_read} 4>&{from_browser_write}', CHROMIUM, *flags],
            pass_fds=(to_browser_read, from_browser_write), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        os.close(to_browser_read)
        os.close(from_browser_write)
        self._buffer = b""
        self._next_id = 0
        self.events = []
        self.session = None

    def close(self):
        try:
            self.send("Browser.close", session=False)
        except Exception:
            pass
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
        os.close(self._to_browser)
        os.close(self._from_browser)

    def _read_message(self):
        while b"\0" not in self._buffer:
            chunk = os.read(self._from_browser, 1 << 16)
            if not chunk:
                raise RuntimeError("chromium closed the DevTools pipe")
            self._buffer += chunk
        message, self._buffer = self._buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, session=True, **params):
        self._next_id += 1
        message = {"id": self._next_id, "method": method, "params": params}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self._to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == self._next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]
            self.events.append(reply)

    def wait_for(self, method):
        for event in self.events:
            if event.get("method") == method:
                return event
        while True:
            event = self._read_message()
            self.events.append(event)
            if event.get("method") == method:
                return event

    def evaluate(self, expression):
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")


def run(*arguments):
    result = subprocess.run([CLI, *map(str, arguments)], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    return result


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    folder = tmp_path_factory.mktemp("report") / "knot1"
    mesh = MESHES / "knot1.off"
    run("build", mesh, "-o", folder, *[a for p in PROXIES for a in ("--proxy", p)], "--gssa-lines", "20000")
    run("verify", mesh, folder)
    run("measure", mesh, folder, "--rays", "20000", "--timed-rays", "2000")
    run("report", folder)
    return folder / "report.html"


@pytest.fixture(scope="module")
def page(report):
    if CHROMIUM is None:
        pytest.skip("chromium is not installed (cmake/bootstrap.sh test installs it)")
    with tempfile.TemporaryDirectory() as profile:
        browser = DevTools(profile)
        try:
            target = next(t for t in browser.send("Target.getTargets")["targetInfos"] if t["type"] == "page")
            browser.session = browser.send("Target.attachToTarget", targetId=target["targetId"], flatten=True)["sessionId"]
            for domain in ["Runtime", "Log", "Page"]:
                browser.send(f"{domain}.enable")
            browser.send("Emulation.setDeviceMetricsOverride", width=1400, height=1000, deviceScaleFactor=1, mobile=False)
            browser.send("Page.navigate", url=report.as_uri())
            browser.wait_for("Page.loadEventFired")
            yield browser
        finally:
            browser.close()


def test_the_page_loads_with_no_console_error(page):
    assert page.evaluate("document.readyState") == "complete"
    problems = []
    for event in page.events:
        method, params = event.get("method"), event.get("params", {})
        if method == "Runtime.exceptionThrown":
            problems.append(params["exceptionDetails"].get("text"))
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            problems.append(params.get("args"))
        elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
            problems.append(params["entry"].get("text"))
    assert problems == []
    # The script ran; what to ship is the first thing under the title, then the recommendation.
    assert page.evaluate("document.getElementById('sortable').dataset.sortable") == "ready"
    first = page.evaluate("document.querySelector('h1').nextElementSibling.id")
    assert first == "ship"
    assert page.evaluate("document.getElementById('ship').nextElementSibling.id") == "recommendation"
    ship = page.evaluate("Array.from(document.querySelectorAll('#ship li')).map(li => li.dataset.use)")
    assert ship == ["control_variate", "eq8", "bounds"]
    sentences = page.evaluate("Array.from(document.querySelectorAll('#recommendation li')).map(li => li.textContent)")
    assert [s.split(",")[0] for s in sentences] == ["For shadow rays through the control variate",
                                                    "For shadow rays through eq. 8", "For exact shadow rays through bounds"]


def test_every_picture_is_there_and_not_blank(page):
    images = page.evaluate("Array.from(document.images).map(i => [i.alt, i.complete, i.naturalWidth, i.naturalHeight])")
    assert len(images) == 4 * len(PROXIES)
    for alt, complete, width, height in images:
        assert complete and width == 192 and height == 192, alt
    for index, (alt, *_) in enumerate(images):
        box = page.evaluate(f"(() => {{ const i = document.images[{index}]; i.scrollIntoView();"
                            f" const r = i.getBoundingClientRect();"
                            f" return [r.left + scrollX, r.top + scrollY, r.width, r.height]; }})()")
        shot = page.send("Page.captureScreenshot", format="png", captureBeyondViewport=True,
                         clip={"x": box[0], "y": box[1], "width": box[2], "height": box[3], "scale": 1})
        picture = PIL.open(io.BytesIO(base64.b64decode(shot["data"]))).convert("L")
        pixels = list(picture.getdata())
        mean = sum(pixels) / len(pixels)
        deviation = (sum((p - mean) ** 2 for p in pixels) / len(pixels)) ** 0.5
        # Something is drawn: a range of greys (a mesh, a shadow), not one flat colour.
        assert max(pixels) - min(pixels) > 40, alt
        assert deviation > 5, alt


def test_the_table_sorts_by_any_column(page):
    column = lambda i: page.evaluate(
        f"Array.from(document.querySelectorAll('#sortable tbody tr')).map(r => r.cells[{i}].dataset.sort)")
    click = lambda i: page.evaluate(f"document.querySelectorAll('#sortable th')[{i}].click()")
    click(2)  # primitives
    ascending = [float(v) for v in column(2)]
    assert ascending == sorted(ascending) and len(ascending) == len(PROXIES)
    click(2)
    assert [float(v) for v in column(2)] == sorted(ascending, reverse=True)
    click(0)  # names, as text
    names = column(0)
    assert names == sorted(names)
    assert page.evaluate("document.querySelectorAll('#sortable th')[0].className") == "sorted-ascending"
