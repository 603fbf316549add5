"""The web view in a real browser: headless Chromium (Debian's) driven by Playwright.

    browser.py PLUMBLINE CASE [--png PNG]

CASE `read-only`: a simulated hold is served read-only; the page loads, shows the map and the
pose, and its time and frame count advance while the flight runs; it offers no buttons and a
command sent anyway is refused (403); a second page that closes mid-stream stops nothing.

CASE `commands`: served with a token; a command with a wrong token is refused and changes
nothing; the kill button with the right token stops the motors (mode Killed on the page and
last in the flight's summary).

CASE `companion`: `plumbline companion --view` replays the bundled XV-11 capture at its own pace
into a UDP socket this script holds; the read-only page shows the SLAM's map and pose, its time
advances, and the mode (which only the autopilot knows) shows as unknown.

CASE `screenshot`: saves the page during an exploration flight as --png (default
docs/web-view.png, the README's picture); run from the repository root.

Loopback only. Every wait is bounded; on any failure the script exits non-zero with a reason.
"""

import argparse
import json
import pathlib
import re
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

from playwright.sync_api import sync_playwright

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
# A long hold at five times real time: the flight outlasts the test, which ends it (or the kill
# does), and the page sees a few simulated seconds per wall-clock second, as a person would.
SIM_ARGS = ["sim", "--scenario", "hold", "--world", "office", "--duration", "3000", "--seed", "3",
            "--realtime", "5", "--json"]
SCREENSHOT_ARGS = ["sim", "--scenario", "explore", "--world", "room", "--seed", "1",
                   "--realtime", "5", "--json"]
SCREENSHOT_AT_S = 35.0
CAPTURE = pathlib.Path(__file__).resolve().parents[2] / "data/captures/neato-xv11/hand_in_box.bin"
WAIT_S = 60.0


def fail(msg):
    print(f"FAIL: {msg}", file=sys.stderr)
    sys.exit(1)


class Sim:
    """A `plumbline sim --view` run; its view's address read from its stderr."""

    def __init__(self, plumbline, extra, sim_args=SIM_ARGS):
        self.proc = subprocess.Popen(
            [plumbline, *sim_args, "--view", "127.0.0.1:0", *extra],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.url = None
        found = threading.Event()

        def read_stderr():
            for line in self.proc.stderr:
                m = re.search(r"view: (http://127\.0\.0\.1:\d+/)", line)
                if m and not found.is_set():
                    self.url = m.group(1)
                    found.set()

        threading.Thread(target=read_stderr, daemon=True).start()
        if not found.wait(WAIT_S):
            self.proc.kill()
            fail("the sim never printed its view address")

    def alive(self):
        return self.proc.poll() is None

    def summary(self, timeout_s):
        """The run's --json summary, once it has ended by itself."""
        try:
            out, _ = self.proc.communicate(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            fail("the flight did not end")
        return json.loads(out.strip().splitlines()[-1])

    def stop(self):
        if self.alive():
            self.proc.send_signal(signal.SIGTERM)
            self.proc.wait(timeout=WAIT_S)


def text(page, selector):
    return page.locator(selector).inner_text()


def wait_until(what, predicate):
    deadline = time.monotonic() + WAIT_S
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    fail(f"timed out waiting for {what}")


def sim_time(page):
    return float(text(page, "#t").split()[0])


def open_page(browser, url):
    page = browser.new_page()
    page.goto(url)
    wait_until("the websocket", lambda: text(page, "#link") == "live")
    wait_until("state frames", lambda: int(page.get_attribute("body", "data-frames") or 0) >= 3)
    return page


def read_only(browser, plumbline):
    sim = Sim(plumbline, [])
    try:
        page = open_page(browser, sim.url)
        wait_until("the map", lambda: page.get_attribute("body", "data-map-version"))
        if "@" not in text(page, "#mapinfo"):
            fail(f"map info not shown: {text(page, '#mapinfo')!r}")
        pose = text(page, "#pose")
        if not re.fullmatch(r"-?\d+\.\d\d, -?\d+\.\d\d, -?\d+\.\d\d m", pose):
            fail(f"pose not shown: {pose!r}")
        frames0 = int(page.get_attribute("body", "data-frames"))
        t0 = sim_time(page)
        wait_until("new frames", lambda: int(page.get_attribute("body", "data-frames")) > frames0 + 5)
        wait_until("the time to advance", lambda: sim_time(page) > t0 + 1.0)
        wait_until("the hold", lambda: text(page, "#mode") == "Hold")
        wait_until("the pose to change", lambda: text(page, "#pose") != pose)
        if page.locator("#controls").is_visible():
            fail("a read-only view shows command buttons")
        status = page.evaluate(
            "fetch('/command', {method: 'POST', body: 'kill'}).then((r) => r.status)"
        )
        if status != 403:
            fail(f"a command to a read-only view got {status}, not 403")
        # A second page that goes away mid-stream.
        other = open_page(browser, sim.url)
        other.close()
        t1 = sim_time(page)
        wait_until("frames after a client left", lambda: sim_time(page) > t1 + 1.0)
        if not sim.alive():
            fail("the flight stopped when a client left")
        stats = json.loads(page.evaluate("fetch('/stats').then((r) => r.text())"))
        if stats["clients_disconnected"] < 1 or stats["commands_refused"] != 1:
            fail(f"the view's counters disagree: {stats}")
        print(f"read-only: map {text(page, '#mapinfo')}, t {sim_time(page):.1f} s, {stats}")
    finally:
        sim.stop()


def companion(browser, plumbline):
    # The autopilot's end of the link: a socket that takes the ODOMETRY and never answers.
    autopilot = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    autopilot.bind(("127.0.0.1", 0))
    port = autopilot.getsockname()[1]
    args = ["companion", "--lidar", "xv11", "--replay", str(CAPTURE), "--realtime",
            "--mavlink", f"udpout:127.0.0.1:{port}", "--json"]
    run = Sim(plumbline, [], args)
    try:
        page = open_page(browser, run.url)
        wait_until("the map", lambda: page.get_attribute("body", "data-map-version"))
        t0 = sim_time(page)
        wait_until("the time to advance", lambda: sim_time(page) > t0 + 1.0)
        if text(page, "#mode") != "-":
            fail(f"the companion's view shows a mode it cannot know: {text(page, '#mode')!r}")
        if page.locator("#controls").is_visible():
            fail("the companion's view shows command buttons")
        print(f"companion: map {text(page, '#mapinfo')}, t {sim_time(page):.1f} s, "
              f"pose {text(page, '#pose')}")
    finally:
        run.stop()
        autopilot.close()


def screenshot(browser, plumbline, path):
    """The README's picture: an exploration flight some way in."""
    sim = Sim(plumbline, [], SCREENSHOT_ARGS)
    try:
        page = open_page(browser, sim.url)
        wait_until("the exploration to get going", lambda: sim_time(page) > SCREENSHOT_AT_S)
        page.screenshot(path=path)
        print(f"screenshot at t {sim_time(page):.1f} s: {path}")
    finally:
        sim.stop()


def commands(browser, plumbline):
    token = "correct-horse"
    sim = Sim(plumbline, ["--view-token", token])
    page = open_page(browser, sim.url + "#token=wrong")
    wait_until("the command buttons", lambda: page.locator("#controls").is_visible())
    wait_until("the hold", lambda: text(page, "#mode") == "Hold")
    page.click("#land")
    wait_until("the refusal", lambda: text(page, "#reply").startswith("403"))
    if text(page, "#mode") != "Hold":
        fail(f"a refused land changed the mode to {text(page, '#mode')}")
    page.fill("#token", token)
    page.click("#kill")
    wait_until("the acceptance", lambda: text(page, "#reply").startswith("202"))
    wait_until("the motors to stop", lambda: text(page, "#mode") == "Killed")
    summary = sim.summary(WAIT_S)
    last_mode = summary["modes"][-1]["mode"]
    view = summary["view"]["stats"]
    if last_mode != "killed" or summary["failsafe"] != "kill_switch":
        fail(f"the flight ended in {last_mode} ({summary['failsafe']}), not killed")
    if (view["commands_refused"], view["commands_accepted"]) != (1, 1):
        fail(f"commands counted wrong: {view}")
    print(f"commands: killed at {summary['modes'][-1]['t_s']:.2f} s, ended {summary['status']}, {view}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("plumbline")
    ap.add_argument("case", choices=["read-only", "commands", "companion", "screenshot"])
    ap.add_argument("--png", default="docs/web-view.png", help="where `screenshot` saves")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as profile, sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            profile,
            executable_path=CHROMIUM,
            args=CHROMIUM_FLAGS,
            headless=True,
            viewport={"width": 960, "height": 600},
        )
        browser = context
        if args.case == "read-only":
            read_only(browser, args.plumbline)
        elif args.case == "commands":
            commands(browser, args.plumbline)
        elif args.case == "companion":
            companion(browser, args.plumbline)
        else:
            screenshot(browser, args.plumbline, args.png)
        context.close()
    print("ok")


if __name__ == "__main__":
    main()
