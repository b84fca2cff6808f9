"""``/metrics`` for a Prometheus scraper.

Three sources, one answer:

* django-prometheus' request counters and latency histograms, kept by its
  middleware in each web process;
* ``common.metrics``: live websockets and database pools of the web processes;
* ``FleetFigures``, read from the database at scrape time: what every
  collector last reported in its heartbeat and the job queue. The robots need
  no open port; a collector that stops beating shows as down.

Under Gunicorn, ``PROMETHEUS_MULTIPROC_DIR`` (set by ftt_site/server/gunicorn.conf.py)
makes every worker write its values to files that each scrape adds up.
Only a bearer token (``FTT_METRICS_TOKEN``) or an address in
``FTT_METRICS_ADDRESSES`` may read it.
"""

import hmac
import ipaddress
import os

from django.conf import settings
from django.http import HttpResponse, JsonResponse
from django.utils import timezone
from django.views.decorators.cache import never_cache
from django.views.decorators.http import require_GET
from prometheus_client import (
    CONTENT_TYPE_LATEST,
    REGISTRY,
    CollectorRegistry,
    generate_latest,
    multiprocess,
)
from prometheus_client.core import CounterMetricFamily, GaugeMetricFamily

from common import jobs
from ftt_site.inbound.lockout import client_address
from rosbridge_app.selectors.collectors import collector_status, collectors
from telemetry.selectors.recordings import snapshots_per_vehicle

COLLECTOR_LABELS = ["collector", "vehicle"]


class FleetFigures:
    """A prometheus_client collector over the database's view of the fleet."""

    def collect(self):
        now = timezone.now()
        up = GaugeMetricFamily(
            "ftt_collector_up", "1 while the collector beats.", labels=COLLECTOR_LABELS
        )
        logging = GaugeMetricFamily(
            "ftt_collector_logging",
            "1 while the collector logs into a leg.",
            labels=COLLECTOR_LABELS,
        )
        spool = GaugeMetricFamily(
            "ftt_collector_spool_records",
            "Records waiting in the robot's spool for the database.",
            labels=COLLECTOR_LABELS,
        )
        stored = CounterMetricFamily(
            "ftt_collector_stored_records",
            "Records the collector wrote to the database since it started.",
            labels=COLLECTOR_LABELS,
        )
        messages = CounterMetricFamily(
            "ftt_collector_input_messages",
            "Messages the collector received per input since it subscribed.",
            labels=[*COLLECTOR_LABELS, "input"],
        )
        age = GaugeMetricFamily(
            "ftt_collector_input_last_message_age_seconds",
            "Seconds since the input's last message, as of the last heartbeat.",
            labels=[*COLLECTOR_LABELS, "input"],
        )
        snapshots = CounterMetricFamily(
            "ftt_collector_snapshots",
            "Black-box snapshots stored for the collector's vehicle.",
            labels=COLLECTOR_LABELS,
        )
        per_vehicle = snapshots_per_vehicle()
        logging_now = 0
        for collector in collectors():
            status = collector_status(collector, now)
            labels = [collector.name, status["vehicle"] or ""]
            up.add_metric(labels, 1 if status["online"] else 0)
            live = status["online"] and status["logging"]
            logging_now += live
            logging.add_metric(labels, 1 if live else 0)
            spool.add_metric(labels, status["pending"])
            stored.add_metric(labels, collector.stored)
            snapshots.add_metric(labels, per_vehicle.get(collector.vehicle_id, 0))
            for name, info in status["inputs"].items():
                messages.add_metric([*labels, name], info.get("count", 0))
                if "age" in info:
                    age.add_metric([*labels, name], info["age"])
        yield from (up, logging, spool, stored, messages, age, snapshots)
        yield GaugeMetricFamily(
            "ftt_collectors_logging", "Collectors logging into a leg now.", value=logging_now
        )
        waiting, oldest = jobs.queue_state(now)
        yield GaugeMetricFamily("ftt_job_queue_length", "Jobs waiting for a worker.", value=waiting)
        yield GaugeMetricFamily(
            "ftt_job_queue_oldest_seconds",
            "How long the oldest waiting job has waited.",
            value=oldest,
        )
        yield GaugeMetricFamily(
            "ftt_job_workers_alive",
            "1 while some job worker beats.",
            value=jobs.worker_running(now),
        )


@never_cache
@require_GET
def metrics(request):
    if not _allowed(request):
        return JsonResponse(
            {"detail": "Metrics need FTT_METRICS_TOKEN or an address in FTT_METRICS_ADDRESSES."},
            status=403,
        )
    fleet = CollectorRegistry(auto_describe=True)
    fleet.register(FleetFigures())
    if "PROMETHEUS_MULTIPROC_DIR" in os.environ:
        processes = CollectorRegistry()
        multiprocess.MultiProcessCollector(processes)
    else:
        processes = REGISTRY
    body = generate_latest(processes) + generate_latest(fleet)
    return HttpResponse(body, content_type=CONTENT_TYPE_LATEST)


def _allowed(request) -> bool:
    token = settings.FTT_METRICS_TOKEN
    sent = request.headers.get("Authorization", "")
    if token and hmac.compare_digest(sent.encode(), f"Bearer {token}".encode()):
        return True
    try:
        address = ipaddress.ip_address(client_address(request) or "")
    except ValueError:
        return False
    return any(address in network for network in settings.FTT_METRICS_NETWORKS)
