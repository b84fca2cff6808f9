"""X-Forwarded-For is believed only from the configured proxies, by one rule
(ftt_site.inbound.proxies) for every use of the client's address: who may read /metrics,
whose failed sign-ins count together."""

import ipaddress
import os

import pytest
import requests
from django.test import Client

from tests.support.web import WebServer

# On SpatiaLite: its server test drives a server of its own on the embedded database.
pytestmark = pytest.mark.spatialite

SCRAPER = "10.9.9.9"


def networks(*nets):
    return [ipaddress.ip_network(net) for net in nets]


@pytest.fixture
def scraper_only(settings):
    settings.FTT_METRICS_NETWORKS = networks(f"{SCRAPER}/32")
    settings.FTT_METRICS_TOKEN = ""
    settings.AXES_FAILURE_LIMIT = 3


def guesses_from(client_kwargs: list[dict], username: str = "ada") -> list[int]:
    return [
        Client(**kwargs).post("/login/", {"username": username, "password": "guess"}).status_code
        for kwargs in client_kwargs
    ]


@pytest.mark.django_db
@pytest.mark.parametrize("behind_proxy", [False, True])
def test_a_client_that_is_no_proxy_cannot_say_where_it_comes_from(
    settings, scraper_only, behind_proxy
):
    settings.FTT_BEHIND_PROXY = behind_proxy
    settings.FTT_PROXY_NETWORKS = networks("10.1.1.1/32")
    direct = {"REMOTE_ADDR": "127.0.0.1", "HTTP_X_FORWARDED_FOR": SCRAPER}
    assert Client(**direct).get("/metrics").status_code == 403
    # Another forwarded address at each guess: the guesses still come from one address.
    codes = guesses_from(
        [{"REMOTE_ADDR": "127.0.0.1", "HTTP_X_FORWARDED_FOR": f"6.6.6.{i}"} for i in range(4)]
    )
    assert codes == [200, 200, 429, 429]


@pytest.mark.django_db
def test_behind_the_configured_proxies_the_address_they_saw_counts(settings, scraper_only):
    settings.FTT_BEHIND_PROXY = True
    settings.FTT_PROXY_NETWORKS = networks("10.1.1.0/24")
    # Two proxies in a row: the first address neither of them is, from the right.
    relayed = {"REMOTE_ADDR": "10.1.1.1", "HTTP_X_FORWARDED_FOR": f"6.6.6.6, {SCRAPER}, 10.1.1.2"}
    assert Client(**relayed).get("/metrics").status_code == 200
    # The same proxy seen on an IPv6 socket.
    mapped = {"REMOTE_ADDR": "::ffff:10.1.1.1", "HTTP_X_FORWARDED_FOR": SCRAPER}
    assert Client(**mapped).get("/metrics").status_code == 200
    # A client's own X-Forwarded-For is what the proxy appends to: not believed.
    forged = {"REMOTE_ADDR": "10.1.1.1", "HTTP_X_FORWARDED_FOR": f"{SCRAPER}, 6.6.6.6"}
    assert Client(**forged).get("/metrics").status_code == 403
    chains = [f"{i}.1.1.1, 6.6.6.6" for i in range(4)]
    codes = guesses_from([{"REMOTE_ADDR": "10.1.1.1", "HTTP_X_FORWARDED_FOR": c} for c in chains])
    assert codes == [200, 200, 429, 429]
    other_browser = {"REMOTE_ADDR": "10.1.1.1", "HTTP_X_FORWARDED_FOR": "6.6.6.7"}
    assert guesses_from([other_browser], username="bea") == [200]


@pytest.fixture(scope="module", params=["0", "1"], ids=["direct", "behind-proxy"])
def server(request, tmp_path_factory):
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    data_dir = tmp_path_factory.mktemp("forwarded")
    env = {
        "FTT_DATA_DIR": str(data_dir),
        "FTT_BEHIND_PROXY": request.param,
        # The proxy is another machine: this test's requests come straight from loopback.
        "FTT_PROXY_ADDRESSES": "10.1.1.1/32",
        "FTT_METRICS_ADDRESSES": f"{SCRAPER}/32",
        "FTT_LOGIN_FAILURE_LIMIT": "3",
    }
    web = WebServer(env, workers=1, log=data_dir / "server.log")
    yield web.start()
    web.stop()


def test_the_production_server_believes_no_direct_client(server):
    """Uvicorn behind Gunicorn would take X-Forwarded-For from loopback by itself."""
    forwarded = {"X-Forwarded-For": SCRAPER}
    assert requests.get(f"{server.url}/metrics", headers=forwarded, timeout=10).status_code == 403
    codes = [
        requests.post(
            f"{server.url}/api/token/",
            data={"username": "nobody", "password": "guess"},
            headers={"X-Forwarded-For": f"6.6.6.{i}"},
            timeout=10,
        ).status_code
        for i in range(4)
    ]
    assert codes == [400, 400, 429, 429]
