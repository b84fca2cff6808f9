"""A robot's token, which the original FTT's node sends in the path, appears in
no line of the production server's log and in no metrics label."""

import os

import pytest
import requests

from tests.support.sites import copy_migrated_database
from tests.support.web import WebServer

# On SpatiaLite: its server test drives a server of its own on the embedded database.
pytestmark = pytest.mark.spatialite


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    if os.environ.get("FTT_DATABASE_URL"):
        pytest.skip("drives a server of its own on the embedded database")
    data_dir = tmp_path_factory.mktemp("log-masks")
    # The access log to standard output, which the test keeps beside the server's own lines.
    web = WebServer(
        {"FTT_DATA_DIR": str(data_dir), "FTT_ACCESS_LOG": "-"},
        workers=1,
        log=data_dir / "server.log",
    )
    copy_migrated_database(data_dir)
    web.python('from events.models import Vehicle; Vehicle.objects.create(key="rover")')
    token = web.manage("ftt_robot_account", "robot-a", "--vehicle", "rover").strip()
    yield web.start(migrate=False), token
    web.stop()


def test_robot_tokens_in_legacy_paths_are_masked_in_the_log_and_the_metrics(server):
    web, token = server
    wrong = "f" * 40
    asked = [
        requests.get(f"{web.url}/legacy/{token}/robot_state", timeout=10),
        requests.post(f"{web.url}/legacy/{token}/pose", data="not json", timeout=10),
        requests.get(f"{web.url}/legacy/{wrong}/robot_state", timeout=10),
        requests.get(f"{web.url}/legacy/{token}/nothing-here", timeout=10),
    ]
    assert all(answer.status_code for answer in asked)
    scraped = requests.get(f"{web.url}/metrics", timeout=10).text
    assert "django_http_responses_total_by_status_view_method_total" in scraped
    assert token not in scraped and wrong not in scraped
    # The log has the requests (access log, Django's warnings), without their tokens.
    log = web.log_path.read_text()
    assert log.count("/legacy/***/") >= len(asked)
    assert token not in log and wrong not in log
