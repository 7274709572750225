"""The commissioning report as a person sees it: rendered by headless Chromium (Debian's ``chromium``),
driven through the DevTools protocol (websocket-client). The page of the four samples must load from disk
with no console error and no failed request, show every section of every drive, the process-image diagram
with its boxes and labels and the plots with their titles, and it takes a screenshot: into the test's
temporary directory on every run, and into docs/report-screenshot.png (the picture in the README) where that
file is missing or ``ECATTOOL_UPDATE_SCREENSHOT=1`` asks for it — a test run never changes a tracked file on its
own (a simulator change would otherwise leave every checkout with a modified picture).

Skipped, with the reason printed, only where no Chromium is installed (CI installs it: .ci/run).
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import ROOT

#: the four samples, relative to the repository root as the README runs them (the Technosoft one, with its .sw
#: image, first: the screenshot shows the top of the page)
SAMPLES = [f"samples/{name}/project.yaml" for name in ("technosoft_ipos", "hdt", "controltechniques", "generic_esi")]
SCREENSHOT = ROOT / "docs" / "report-screenshot.png"
CHROMIUM = next((p for p in (shutil.which("chromium"), "/usr/bin/chromium", shutil.which("chromium-browser"))
                 if p and os.path.exists(p)), None)
#: how long the browser may take to start and to load the page (bounds of the waits, not assertions on time)
START_S, LOAD_S = 60.0, 60.0


class DevTools:
    """A DevTools-protocol session on one page target (flat mode: one websocket, commands with a sessionId)."""

    def __init__(self, ws_url: str) -> None:
        import websocket

        self.ws = websocket.create_connection(ws_url, timeout=LOAD_S, suppress_origin=True)
        self.next_id = 0
        self.events: list[dict[str, Any]] = []
        self.session: str | None = None

    def send(self, method: str, **params: Any) -> dict[str, Any]:
        self.next_id += 1
        msg: dict[str, Any] = {"id": self.next_id, "method": method, "params": params}
        if self.session is not None:
            msg["sessionId"] = self.session
        self.ws.send(json.dumps(msg))
        while True:
            reply = json.loads(self.ws.recv())
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise AssertionError(f"{method}: {reply['error']}")
                result: dict[str, Any] = reply.get("result", {})
                return result
            self.events.append(reply)

    def wait_for(self, method: str) -> dict[str, Any]:
        deadline = time.monotonic() + LOAD_S
        seen = 0
        while time.monotonic() < deadline:
            for e in self.events[seen:]:
                if e.get("method") == method:
                    return e
            seen = len(self.events)
            self.events.append(json.loads(self.ws.recv()))
        raise AssertionError(f"no {method} within {LOAD_S} s")

    def evaluate(self, expression: str) -> Any:
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True)
        if "exceptionDetails" in result:
            raise AssertionError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")


@pytest.fixture(scope="module")
def browser(tmp_path_factory: pytest.TempPathFactory) -> Iterator[DevTools]:
    if CHROMIUM is None:
        reason = "no Chromium installed (apt-get install chromium); the report's browser test is skipped"
        print(f"SKIPPED: {reason}")
        pytest.skip(reason)
    profile = tmp_path_factory.mktemp("chromium-profile")
    proc = subprocess.Popen(
        [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-dev-shm-usage", "--hide-scrollbars", f"--user-data-dir={profile}", "--remote-debugging-port=0",
         "--window-size=1200,900", "about:blank"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        port_file = profile / "DevToolsActivePort"
        deadline = time.monotonic() + START_S
        while not (port_file.exists() and len(port_file.read_text().splitlines()) >= 2):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"{CHROMIUM} did not start (exit status {proc.poll()})")
            time.sleep(0.05)
        port, path = port_file.read_text().splitlines()[:2]
        tools = DevTools(f"ws://127.0.0.1:{port}{path}")
        target = tools.send("Target.createTarget", url="about:blank")["targetId"]
        tools.session = tools.send("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        yield tools
        tools.ws.close()
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=20)
        except subprocess.TimeoutExpired:  # pragma: no cover
            proc.kill()
            proc.wait()


@pytest.fixture(scope="module")
def page(browser: DevTools, tmp_path_factory: pytest.TempPathFactory) -> DevTools:
    """The report of the four samples, loaded (from disk) in the browser."""
    from ecattool.cli import main

    report = tmp_path_factory.mktemp("report") / "report.html"
    os.environ["SOURCE_DATE_EPOCH"] = "1767225600"  # a fixed "generated" line: the screenshot is reproducible
    cwd = os.getcwd()
    os.chdir(ROOT)
    try:
        main(["commission", *SAMPLES, "--report", str(report), "--json"])
    except SystemExit as exc:
        assert exc.code == 0
    finally:
        os.chdir(cwd)
        del os.environ["SOURCE_DATE_EPOCH"]
    for domain in ("Page", "Runtime", "Log", "Network"):
        browser.send(f"{domain}.enable")
    browser.send("Emulation.setDeviceMetricsOverride", width=1200, height=900, deviceScaleFactor=1, mobile=False)
    browser.send("Page.navigate", url=report.as_uri())
    browser.wait_for("Page.loadEventFired")
    return browser


def test_page_loads_without_console_errors_or_requests(page: DevTools) -> None:
    errors = [e for e in page.events if e.get("method") == "Runtime.exceptionThrown"
              or (e.get("method") == "Runtime.consoleAPICalled" and e["params"]["type"] in ("error", "assert"))
              or (e.get("method") == "Log.entryAdded" and e["params"]["entry"]["level"] == "error")
              or e.get("method") == "Network.loadingFailed"]
    assert not errors, errors
    # self-contained: the page is the only thing loaded
    requested = [e["params"]["request"]["url"] for e in page.events if e.get("method") == "Network.requestWillBeSent"]
    assert requested and all(u.startswith("file://") and u.endswith("report.html") for u in requested), requested


def test_every_section_is_shown_for_every_drive(page: DevTools) -> None:
    drives = page.evaluate("""[...document.querySelectorAll('section.drive')].map(s => ({
        title: s.querySelector('h3').innerText,
        sections: [...s.querySelectorAll('h4')].map(h => h.innerText),
        visible: [...s.querySelectorAll('h4')].every(h => h.getBoundingClientRect().height > 0)}))""")
    assert [d["title"].split(" (")[0] for d in drives] == ["Drive z_axis", "Drive table", "Drive feed", "Drive joint1"]
    for d in drives:
        assert "OK" in d["title"] and d["visible"]
        assert d["sections"] == ["Steps", "Process image", "Startup list as sent", ".sw setup image", "State timeline",
                                 "Commissioning move"]
    findings = page.evaluate("[...document.querySelectorAll('h3.findings')].length")
    assert findings == len(SAMPLES)


def test_diagram_is_drawn_with_its_labels(page: DevTools) -> None:
    boxes = page.evaluate("""[...document.querySelectorAll('section.drive')].map(s =>
        [...s.querySelectorAll('.diagram g.entry')].map(g => {
            const r = g.getBoundingClientRect();
            return {object: g.dataset.object, offset: g.dataset.offset, w: r.width, h: r.height,
                    text: [...g.querySelectorAll('text')].map(t => t.textContent).join(' ')};
        }))""")
    z_axis = boxes[0]  # samples/technosoft_ipos: its own mapping
    assert [(b["object"], b["offset"]) for b in z_axis] == [
        ("0x6040:00", "0.0"), ("0x6060:00", "2.0"), ("0x607A:00", "3.0"),
        ("0x6041:00", "0.0"), ("0x6061:00", "2.0"), ("0x6064:00", "3.0"), ("0x6063:00", "7.0")]
    for drive in boxes:
        assert drive and all(b["w"] > 10 and b["h"] > 10 for b in drive)  # rendered, not just in the markup
        assert all(b["object"] in b["text"] for b in drive)
    assert "Controlword" in z_axis[0]["text"] and "0.0 · 16 bit" in z_axis[0]["text"]


def test_plots_are_drawn_with_their_titles_and_labels(page: DevTools) -> None:
    plots = page.evaluate("""[...document.querySelectorAll('section.drive')].map(s =>
        [...s.querySelectorAll('div.timeline, div.plot')].map(p => {
            const svg = p.querySelector('svg'); const r = svg.getBoundingClientRect();
            return {title: p.dataset.title || 'timeline', w: r.width, h: r.height, lines: svg.querySelectorAll('path').length,
                    text: [...svg.querySelectorAll('text')].map(t => t.textContent).join(' | ')};
        }))""")
    for drive in plots:
        assert all(p["w"] > 300 and p["h"] > 100 and p["lines"] > 5 for p in drive)
        timeline = drive[0]
        assert "EtherCAT" in timeline["text"] and "CiA-402" in timeline["text"] and "operation enabled" in timeline["text"]
        position, velocity = drive[1], drive[2]
        assert "6064h position actual" in position["text"] and "time [ms]" in position["text"]
        assert "606Ch velocity actual" in velocity["text"] or "demand velocity" in velocity["text"]
    z_axis = plots[0]
    assert [p["title"] for p in z_axis] == ["timeline", "Position (user units, um)", "Velocity (user units, mm/s)",
                                            "Internal units (counts)", "Following error and torque"]
    assert "position [um]" in z_axis[1]["text"] and "velocity [counts/s]" in z_axis[3]["text"]


def test_screenshot_for_the_readme(page: DevTools, tmp_path: Path) -> None:
    """The top of the page down to the first drive's position plot: header, findings, identity, steps, process
    image, startup summary, .sw blocks, timeline and the move."""
    bottom = page.evaluate("""(() => { const p = document.querySelectorAll('section.drive')[0]
        .querySelectorAll('div.plot')[0]; const r = p.getBoundingClientRect(); return r.bottom + window.scrollY + 8; })()""")
    shot = page.send("Page.captureScreenshot", format="png", captureBeyondViewport=True,
                     clip={"x": 0, "y": 0, "width": 1200, "height": bottom, "scale": 1})
    data = base64.b64decode(shot["data"])
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 50_000
    (tmp_path / SCREENSHOT.name).write_bytes(data)
    print(f"screenshot: {tmp_path / SCREENSHOT.name}")
    if not SCREENSHOT.exists() or os.environ.get("ECATTOOL_UPDATE_SCREENSHOT") == "1":
        SCREENSHOT.write_bytes(data)
