"""/healthz, /readyz and /metrics as a load balancer and a Prometheus scraper see them."""

import json
import re
from pathlib import Path

import pytest
from django.utils import timezone
from prometheus_client.parser import text_string_to_metric_families

from common import jobs
from events.models import Vehicle
from rosbridge_app.services.collectors import heartbeat

# On SpatiaLite too: the health check asks each database its own way.
pytestmark = [pytest.mark.spatialite, pytest.mark.django_db]


def samples(response) -> dict[tuple, float]:
    """{(sample name, sorted labels): value} of a Prometheus text answer."""
    found = {}
    for family in text_string_to_metric_families(response.content.decode()):
        for sample in family.samples:
            found[(sample.name, tuple(sorted(sample.labels.items())))] = sample.value
    return found


def test_liveness_answers_without_a_session_or_a_query(client, django_assert_num_queries):
    with django_assert_num_queries(0):
        response = client.get("/healthz")
    assert response.status_code == 200
    assert response.json() == {"status": "alive"}
    assert "sessionid" not in response.cookies


def test_readiness_says_what_is_missing_and_when_to_ask_again(client):
    response = client.get("/readyz")
    assert response.status_code == 503
    assert response["Retry-After"] == "10"
    checks = response.json()["checks"]
    assert checks["database"]["ok"] and checks["migrations"]["ok"] and checks["disk"]["ok"]
    assert not checks["job_worker"]["ok"]
    assert "reports and imports wait" in checks["job_worker"]["detail"]

    jobs.beat("worker-1")
    response = client.get("/readyz")
    assert response.status_code == 200, response.json()
    assert response.json()["status"] == "ready"


def test_readiness_fails_when_the_disk_is_nearly_full(client, settings):
    jobs.beat("worker-1")
    settings.FTT_READY_MIN_FREE_MB = 10**12
    response = client.get("/readyz")
    assert response.status_code == 503
    assert "MB free under" in response.json()["checks"]["disk"]["detail"]


def test_metrics_need_an_allowed_address_or_the_token(client, settings):
    settings.FTT_METRICS_NETWORKS = []
    settings.FTT_METRICS_TOKEN = "s3cret-scraper"
    assert client.get("/metrics").status_code == 403
    assert client.get("/metrics", headers={"Authorization": "Bearer wrong"}).status_code == 403
    response = client.get("/metrics", headers={"Authorization": "Bearer s3cret-scraper"})
    assert response.status_code == 200
    assert response["Content-Type"].startswith("text/plain")


def test_metrics_count_requests_and_show_each_collector(client):
    vehicle = Vehicle.objects.create(key="husky", short_description="Husky")
    heartbeat(
        "husky-collector",
        vehicle=vehicle,
        logging=True,
        pending=42,
        stored=1234,
        inputs={"gps": {"topic": "/fix", "count": 77, "last_received": timezone.now().isoformat()}},
    )
    before = samples(client.get("/metrics"))
    client.get("/healthz")
    after = samples(client.get("/metrics"))

    labels = (("collector", "husky-collector"), ("vehicle", "husky"))
    assert after[("ftt_collector_up", labels)] == 1
    assert after[("ftt_collector_logging", labels)] == 1
    assert after[("ftt_collector_spool_records", labels)] == 42
    assert after[("ftt_collector_stored_records_total", labels)] == 1234
    gps = (*labels[:1], ("input", "gps"), labels[1])
    assert after[("ftt_collector_input_messages_total", gps)] == 77
    assert after[("ftt_collector_input_last_message_age_seconds", gps)] < 60
    assert after[("ftt_collectors_logging", ())] == 1
    assert after[("ftt_job_queue_length", ())] == 0

    def health_answers(found):
        return sum(
            value
            for (name, labels), value in found.items()
            if name == "django_http_responses_total_by_status_view_method_total"
            and dict(labels).get("view") == "healthz"
        )

    assert health_answers(after) == health_answers(before) + 1


def test_the_example_dashboard_asks_only_for_series_that_exist(client):
    vehicle = Vehicle.objects.create(key="husky", short_description="Husky")
    heartbeat(
        "husky-collector",
        vehicle=vehicle,
        inputs={"gps": {"count": 1, "last_received": timezone.now().isoformat()}},
    )
    client.get("/healthz")
    served = set(samples_names(client.get("/metrics")))
    dashboard = json.loads((Path(__file__).parents[2] / "docs/grafana-dashboard.json").read_text())
    asked = {
        name
        for panel in dashboard["panels"]
        for target in panel["targets"]
        for name in re.findall(r"\b(?:ftt|django)_[a-z_]+", target["expr"])
    }
    assert asked, "the dashboard asks for nothing"
    assert asked <= served, asked - served


def samples_names(response) -> list[str]:
    return [
        sample.name
        for family in text_string_to_metric_families(response.content.decode())
        for sample in family.samples
    ]
