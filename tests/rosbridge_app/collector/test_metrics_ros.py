"""A scraper sees a logging robot's figures move, from the collector's heartbeats alone."""

import pytest
from prometheus_client.parser import text_string_to_metric_families

from tests.support.ros import requires_ros, wait_for

pytestmark = [pytest.mark.ros, requires_ros]


def figures(client) -> dict[tuple, float]:
    response = client.get("/metrics")
    assert response.status_code == 200
    found = {}
    for family in text_string_to_metric_families(response.content.decode()):
        for sample in family.samples:
            found[(sample.name, tuple(sorted(sample.labels.items())))] = sample.value
    return found


def test_a_scrape_follows_a_simulated_robot(start_collector, procs, client):
    procs.start(
        "ftt_simulate",
        "--switch-every",
        "2",
        "--gps-rate",
        "5",
        "--tf-rate",
        "10",
        "--camera-rate",
        "0",
        "--map-size",
        "40",
        name="simulator",
    )
    start_collector("metrics-bot", args=["--start-logging"])
    labels = (("collector", "metrics-bot"), ("vehicle", "ros-bot"))
    gps = (labels[0], ("input", "gps_fix"), labels[1])

    def stored(found):
        return found.get(("ftt_collector_stored_records_total", labels), 0)

    first = {}

    def logging_and_storing():
        first.update(figures(client))
        return first.get(("ftt_collector_logging", labels)) == 1 and stored(first) > 0

    wait_for(logging_and_storing, 40, what="the collector logging and storing")
    assert first[("ftt_collector_up", labels)] == 1
    assert first[("ftt_collectors_logging", ())] >= 1

    later = {}

    def moved():
        later.update(figures(client))
        return stored(later) > stored(first) and later.get(
            ("ftt_collector_input_messages_total", gps), 0
        ) > first.get(("ftt_collector_input_messages_total", gps), 0)

    wait_for(moved, 20, what="the stored records and GPS messages counted up")
    assert later[("ftt_collector_input_last_message_age_seconds", gps)] < 5
    assert later[("ftt_collector_spool_records", labels)] < 1000
