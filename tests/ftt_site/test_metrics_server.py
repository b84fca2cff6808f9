"""/metrics on the production server: the workers' counts add up in one scrape."""

import os

import pytest
import requests
from prometheus_client.parser import text_string_to_metric_families

from tests.support.web import WebServer

# On SpatiaLite only: drives a server of its own on the embedded database.
pytestmark = pytest.mark.spatialite


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    data_dir = tmp_path_factory.mktemp("metrics-server")
    web = WebServer({"FTT_DATA_DIR": str(data_dir)}, workers=2, log=data_dir / "server.log")
    yield web.start()
    web.stop()


def health_answers(server) -> float:
    answer = requests.get(f"{server.url}/metrics", timeout=10)
    assert answer.status_code == 200, answer.text[:500]
    total = 0.0
    for family in text_string_to_metric_families(answer.text):
        for sample in family.samples:
            if (
                sample.name == "django_http_responses_total_by_status_view_method_total"
                and sample.labels.get("view") == "healthz"
            ):
                total += sample.value
    return total


def test_every_workers_requests_are_counted(server):
    before = health_answers(server)
    with requests.Session() as first, requests.Session() as second:
        for _ in range(20):
            # Two keep-alive connections, so both workers are likely to answer some.
            assert first.get(f"{server.url}/healthz", timeout=10).status_code == 200
            assert second.get(f"{server.url}/healthz", timeout=10).status_code == 200
    assert health_answers(server) == before + 40


def test_readiness_on_a_fresh_server_names_the_missing_worker(server):
    answer = requests.get(f"{server.url}/readyz", timeout=10)
    assert answer.status_code == 503
    assert answer.headers["Retry-After"] == "10"
    assert answer.json()["checks"]["migrations"]["ok"]
    assert not answer.json()["checks"]["job_worker"]["ok"]
