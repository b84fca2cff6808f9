"""What a web process counts about itself for Prometheus (served by ftt_site.monitoring.metrics).

Under Gunicorn each worker keeps its own values; prometheus_client's
multiprocess mode adds them up at scrape time, so gauges say how they combine.
"""

from prometheus_client import Gauge

LIVE_CONNECTIONS = Gauge(
    "ftt_live_connections",
    "Open live-update websockets of browsers.",
    multiprocess_mode="livesum",
)
DB_POOL_IN_USE = Gauge(
    "ftt_db_pool_connections_in_use",
    "Database connections of the web processes' pools handed out right now.",
    multiprocess_mode="livesum",
)
DB_POOL_WAITING = Gauge(
    "ftt_db_pool_requests_waiting",
    "Requests waiting for a database connection from a pool.",
    multiprocess_mode="livesum",
)


def observe_pool(pool) -> None:
    """Copy a psycopg pool's figures into the gauges (``pool`` may be None: no pool)."""
    if pool is None:
        return
    stats = pool.get_stats()
    DB_POOL_IN_USE.set(stats.get("pool_size", 0) - stats.get("pool_available", 0))
    DB_POOL_WAITING.set(stats.get("requests_waiting", 0))
