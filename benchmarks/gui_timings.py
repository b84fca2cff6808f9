"""How fast the cockpit answers: page load to interactive and the main actions.

Starts the production server on a fresh SpatiaLite file, makes a leg with --segments take-overs
and GPS tracks, drives Chromium at the tablet size (1024x768, touch) and prints
the median and the slowest of --repeat runs per action, measured from the tap
until the page shows the result (tested at every animation frame; the page load
from the navigation, with an empty HTTP cache as routing leaves it).  Target:
page interactive <= 1.5 s, each action <= 300 ms; a stalled or cut link shown,
live again once it is back, and what was kept during a cut sent, <= 5 s each.
Run: .venv/bin/python benchmarks/gui_timings.py [--repeat 5]
The long leg (issue 49: 250 segments, the main thread's busy share and
switch -> banner beside main) is benchmarks/long_leg.py's; --long-leg runs it
with the arguments that follow:
  .venv/bin/python benchmarks/gui_timings.py --long-leg --main /work/main --segments 250
"""

import argparse
import json
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
os.environ.setdefault("DJANGO_ALLOW_ASYNC_UNSAFE", "true")

from playwright.sync_api import expect, sync_playwright  # noqa: E402

from benchmarks.cockpit_setup import OPERATOR_AND_SHIFT  # noqa: E402
from tests.e2e.link import Link  # noqa: E402
from tests.support.browser import PASSWORD, Server, login, system_chromium  # noqa: E402

SETUP = (
    OPERATOR_AND_SHIFT
    + """
other = logs.create_leg(shift=s, weather_id="sunny")
leg = logs.create_leg(shift=s, weather_id="sunny")
for i in range({segments}):
    auto = segments.report_mode(leg, "auto").master
    fixes = [pose_writes.GpsFix(7.0 + i * 1e-3, 50.0 + j * 1e-5) for j in range(200)]
    pose_writes.store_poses(auto, fixes)
    segments.report_mode(leg, "ito")
segments.report_mode(leg, "auto")
from rosbridge_app.services import collectors
collectors.heartbeat("bench-collector", vehicle=v, logging=True, leg=leg)
print(json.dumps({{"event": e.pk, "shift": s.pk, "leg": leg.pk, "other": other.pk}}))
"""
)


def timed(action, check) -> float:
    start = time.perf_counter()
    action()
    check()
    return (time.perf_counter() - start) * 1000


def until(page, predicate: str, arg=None):
    """Waits until ``predicate`` (JavaScript) holds, tested at every animation
    frame: Playwright's expect() retries after 100, 250, 500 and 1000 ms, so its
    figures jump between those steps."""
    return lambda: page.wait_for_function(predicate, arg=arg, polling="raf", timeout=15000)


ROWS = "document.querySelectorAll('#segment-table tbody tr')"
CHILD = "document.querySelectorAll('#segment-table tbody tr.child')[i]"
SELECTED = "document.querySelector('#segment-table tbody tr.selected')"
BADGE = "(text) => document.querySelector('#live-status').textContent === text"
SHOWN = "(e) => Boolean(e && e.checkVisibility())"
DRAWN = "#gps-map[data-tracks]:not([data-tracks='0'])"
NOTE = "#segment-dialog .notes li"
LOST = "() => document.querySelector('#mode-panel').dataset.link === 'lost'"


def link_figures(browser, server, url, repeat, figures):
    """The link between browser and server stalls (half-open: nothing gets through)
    or is cut, and comes back: how long until the page says so (tests/e2e/link.py)."""
    link = Link(server)
    page = browser.new_page(viewport={"width": 1024, "height": 768}, has_touch=True)
    page.route("**/tiles/**", lambda r: r.fulfill(status=404))
    try:
        login(page, link, "otto")
        page.goto(url.replace(server.url, link.url))
        expect(page.locator("#live-status")).to_have_text("live")
        for _ in range(repeat):
            for name, breaks, shown in (
                ("link stalled -> stale shown", link.stall, "stale"),
                ("link cut -> reconnecting shown", link.cut, "reconnecting…"),
            ):
                figures.setdefault(name, []).append(timed(breaks, until(page, BADGE, shown)))
                figures.setdefault("link back -> live again", []).append(
                    timed(link.restore, until(page, BADGE, "live"))
                )
        # A note made during a cut waits in the browser (outbox.js) until the link is back.
        page.locator("#segment-table tbody tr.child").first.click()
        page.locator("#segment-edit").click()
        dialog = page.locator("#segment-dialog")
        for i in range(repeat):
            figures.setdefault("link cut -> stale shown (mode banner)", []).append(
                timed(link.cut, until(page, LOST))
            )
            dialog.locator("textarea[name=text]").fill(f"Kept during cut {i}")
            dialog.get_by_role("button", name="Add note").click()
            expect(page.locator("#outbox")).to_have_text("1 waiting to send")
            figures.setdefault("link back -> queue sent", []).append(
                timed(link.restore, until(page, "() => document.querySelector('#outbox').hidden"))
            )
            expect(page.locator("#mode-panel")).to_have_attribute("data-link", "live")
    finally:
        page.close()
        link.close()


def main():
    if "--long-leg" in sys.argv:
        from benchmarks import long_leg

        sys.argv = [long_leg.__file__, *sys.argv[sys.argv.index("--long-leg") + 1 :]]
        return long_leg.main()
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--segments", type=int, default=20)
    parser.add_argument(
        "--long-leg",
        action="store_true",
        help="run benchmarks/long_leg.py instead, with the arguments after this one",
    )
    args = parser.parse_args()
    server = Server(Path(tempfile.mkdtemp()), "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png")
    server.start()
    figures: dict[str, list[float]] = {}
    try:
        out = server.python(SETUP.format(password=PASSWORD, segments=args.segments))
        ids = json.loads(out.strip().splitlines()[-1])
        url = f"{server.url}/?event={ids['event']}&shift={ids['shift']}&leg={ids['leg']}"
        with sync_playwright() as p:
            exe = system_chromium()
            browser = p.chromium.launch(
                **({"executable_path": exe} if exe else {}), args=["--no-sandbox"]
            )
            page = browser.new_page(
                viewport={"width": 1024, "height": 768}, has_touch=True, is_mobile=True
            )
            page.route("**/tiles/**", lambda r: r.fulfill(status=404))
            login(page, server, "otto")
            rows = page.locator("#segment-table tbody tr")
            for _ in range(args.repeat):
                figures.setdefault("page interactive (load, segments, map)", []).append(
                    timed(
                        lambda: page.goto(url, wait_until="commit"),
                        until(page, f"() => document.querySelector({DRAWN!r})"),
                    )
                )
                expect(rows).to_have_count(2 * args.segments + 1)
            for i in range(args.repeat):
                row = page.locator("#segment-table tbody tr.child").nth(i)
                figures.setdefault("select a segment (list, map, address)", []).append(
                    timed(
                        row.click, until(page, f"(i) => {CHILD}.classList.contains('selected')", i)
                    ),
                )
                count = rows.count()
                figures.setdefault("New take-over (after the question)", []).append(
                    timed(
                        lambda: (
                            page.locator("#segment-new").click(),
                            page.get_by_role("button", name="Record take-over").click(),
                        ),
                        until(page, f"(n) => {ROWS}.length === n", count + 1),
                    )
                    if page.locator("#mode-name").text_content() == "AUTO"
                    else timed(
                        lambda: page.locator("#segment-new").click(),
                        until(page, f"(n) => {ROWS}.length === n", count + 1),
                    )
                )
                # New selected the take-over it recorded, which quick reasons annotate.
                figures.setdefault("quick reason (the open take-over)", []).append(
                    timed(
                        lambda: page.locator("[data-quick='safety']").click(),
                        until(page, f"() => {SELECTED}.cells[2].textContent === 'Safety'"),
                    )
                )
                expect(page.locator("#segment-end")).to_be_enabled()
                figures.setdefault("End a segment", []).append(
                    timed(
                        lambda: page.locator("#segment-end").click(),
                        until(page, f"() => {SELECTED}.cells[7].textContent === 'closed'"),
                    )
                )
                dialog = page.locator("#segment-dialog")
                figures.setdefault("open the segment dialog", []).append(
                    timed(
                        lambda: page.locator("#segment-edit").click(),
                        until(page, f"() => ({SHOWN})(document.querySelector({NOTE!r}))"),
                    )
                )
                dialog.get_by_role("button", name="Close").click()
                for leg in ("other", "leg"):
                    figures.setdefault("switch leg", []).append(
                        timed(
                            lambda leg=leg: page.select_option("#pick-leg", str(ids[leg])),
                            until(
                                page,
                                f"""([leg, empty]) => location.search.includes(`leg=${{leg}}`)
                                && ({SHOWN})(document.querySelector(
                                    empty ? '#segments-empty' : '#segment-table tbody tr'))""",
                                [ids[leg], leg == "other"],
                            ),
                        )
                    )
                dialog = page.locator("#form-dialog")
                figures.setdefault("open the New leg dialog (fields from the server)", []).append(
                    timed(
                        lambda: page.locator('[data-action="new"][data-level="leg"]').click(),
                        until(
                            page,
                            f"""() => [...document.querySelectorAll('#form-dialog label')].some(
                                (l) => l.textContent.startsWith('Weather') && ({SHOWN})(l))""",
                        ),
                    )
                )
                dialog.get_by_role("button", name="Cancel").click()
                vehicle = page.locator(".fleet-vehicle").first
                figures.setdefault("open the fleet view", []).append(
                    timed(
                        lambda: page.locator("#toggle-fleet").click(),
                        until(page, f"() => ({SHOWN})(document.querySelector('.fleet-vehicle'))"),
                    )
                )
                figures.setdefault("open a vehicle's cockpit from the fleet", []).append(
                    timed(
                        vehicle.click,
                        until(
                            page,
                            f"""() => ({SHOWN})(document.querySelector('#cockpit'))
                            && ({SHOWN})(document.querySelector('#segment-table tbody tr'))""",
                        ),
                    )
                )
            link_figures(browser, server, url, args.repeat, figures)
            browser.close()
    finally:
        server.stop()
    print(f"load average {os.getloadavg()[0]:.2f} (1 min) at the end")
    print(f"{'action':45} {'median ms':>10} {'max ms':>8} {'target':>7}  (n, tablet 1024x768)")
    for name, values in figures.items():
        target = 1500 if name.startswith("page") else 5000 if name.startswith("link") else 300
        median, most = statistics.median(values), max(values)
        verdict = "ok" if median <= target else "OVER"
        print(f"{name:45} {median:10.0f} {most:8.0f} {target:7d}  ({len(values)}) {verdict}")


if __name__ == "__main__":
    main()
