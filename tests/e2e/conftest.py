"""Browser tests: Debian's Chromium driven by Playwright against a real server.

The server is the production one (Gunicorn with a Uvicorn worker, as
scripts/run.sh starts it) in a process of its own on the embedded SpatiaLite
default with no broker, and the "robot" writes from yet another process, so
live updates are tested the way they happen in the field.
"""

import io
import itertools
import os
import shutil
import signal
import time

import pytest
from PIL import Image

from tests.e2e.link import Link
from tests.support.browser import (
    ARTIFACTS,
    Server,
    add_users,
    drop_database,
    fresh_database,
    open_leg_code,
    system_chromium,
)
from tests.support.databases import migrated_postgres_template

# Playwright's sync API keeps an event loop in the test thread.
os.environ.setdefault("DJANGO_ALLOW_ASYNC_UNSAFE", "true")


@pytest.fixture(scope="session")
def browser_type_launch_args(browser_type_launch_args):
    executable = os.environ.get("FTT_CHROMIUM") or system_chromium()
    return {
        **browser_type_launch_args,
        **({"executable_path": executable} if executable else {}),
        "args": [
            *browser_type_launch_args.get("args", []),
            "--no-sandbox",
            "--disable-gpu",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--no-first-run",
            "--disable-quic",
        ],
    }


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    report = yield
    server = _running_server
    if report.failed and server is not None and server.process.poll() is None:
        # The server's thread stacks at the moment of failure, in its log.
        server.process.send_signal(signal.SIGUSR1)
    return report


_running_server = None


def _tile_url() -> str:
    # A loopback tile host; tests answer it with page.route or leave it dead.
    return "http://127.0.0.1:9/tiles/{z}/{x}/{y}.png"


@pytest.fixture(scope="session")
def server(tmp_path_factory):
    global _running_server
    srv = Server(tmp_path_factory.mktemp("ftt-e2e"), _tile_url())
    srv.start()
    _running_server = srv
    add_users(srv)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def postgres_server(tmp_path_factory):
    """A server of its own on a fresh PostgreSQL database, for several writers at
    once (collectors of a fleet): SpatiaLite lets one write at a time."""
    global _running_server
    url = os.environ.get("FTT_DATABASE_URL", "")
    if not url.startswith(("postgis://", "postgres://", "postgresql://")):
        pytest.skip("needs FTT_DATABASE_URL naming a PostgreSQL server (scripts/test.sh sets it)")
    # A copy of the migrated template, so the server finds nothing to migrate.
    database = fresh_database(url, "e2e", migrated_postgres_template())
    srv = Server(
        tmp_path_factory.mktemp("ftt-e2e-postgres"),
        _tile_url(),
        database_url=database,
        name="server-postgres",
    )
    srv.start()
    before, _running_server = _running_server, srv
    add_users(srv)
    yield srv
    srv.stop()
    _running_server = before
    drop_database(database)


_numbers = itertools.count(1)


@pytest.fixture
def open_leg(server):
    """A vehicle with an open test event, shift and leg, made in a separate process."""
    key = f"rover-{next(_numbers)}-{int(time.time() * 1000) % 100000}"
    server.python(open_leg_code(key))
    return key


@pytest.fixture
def link(server):
    """The server behind a link the test can cut or stall (tests/e2e/link.py);
    pages opened at ``link.url`` reach the server only through it."""
    proxy = Link(server)
    yield proxy
    proxy.close()


@pytest.fixture
def shot(request):
    """Save a numbered screenshot of the page as a test artifact."""
    folder = ARTIFACTS / request.node.name
    shutil.rmtree(folder, ignore_errors=True)  # no pictures left from an earlier run
    folder.mkdir(parents=True)
    counter = iter(range(1, 1000))

    def take(page, name: str, full_page: bool = True):
        # A modal's backdrop covers the window, not the page: a whole-page
        # picture of one shows the part above the window undimmed.
        page.screenshot(path=str(folder / f"{next(counter):02d}-{name}.png"), full_page=full_page)

    return take


@pytest.fixture
def tiles(page):
    """Answer tile requests with a tiny grey PNG, as a reachable tile server would."""
    buffer = io.BytesIO()
    Image.new("RGB", (256, 256), (200, 200, 200)).save(buffer, format="PNG")
    png = buffer.getvalue()
    page.route("**/tiles/**", lambda route: route.fulfill(body=png, content_type="image/png"))
    return png


def pytest_collection_modifyitems(items):
    """The field walk starts from a new installation (its first-run hint needs no
    vehicle yet); the tests share one server, so it runs first."""
    items.sort(key=lambda item: item.path.name != "test_field_walk.py")
