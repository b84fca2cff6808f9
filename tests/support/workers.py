"""What one pytest process owns when pytest-xdist spreads the tests over several.

pytest-django gives each worker its own test database (``test_ftt_gw1``); this
module gives it its own ROS domain and Redis database, so that two workers
never hear each other's topics or channel groups. Without xdist the process
is worker 0 and keeps what scripts/test.sh chose.
"""

import os
from urllib.parse import urlsplit, urlunsplit

# "gw3" -> 3; a run without xdist is worker 0.
INDEX = int(os.environ.get("PYTEST_XDIST_WORKER", "gw0").removeprefix("gw"))


def redis_url(url: str) -> str:
    """``url`` with its database number moved up by this worker's index."""
    parts = urlsplit(url)
    db = int(parts.path.strip("/") or 0) + INDEX
    return urlunsplit(parts._replace(path=f"/{db}"))


_assigned = False


def assign_worker_resources() -> None:
    """Moves this process's ROS domain and Redis database to the worker's own,
    before rclpy or a channel layer reads them (the processes the tests start
    inherit them). Once per process: a conftest given on the command line is
    imported before the root conftest's pytest_configure, and its imports
    call this first."""
    global _assigned
    if _assigned:
        return
    _assigned = True
    base = os.environ.get("FTT_ROS_DOMAIN_ID") or os.environ.get("ROS_DOMAIN_ID")
    if base is None:
        base = str(40 + os.getppid() % 20)
    domain = str(int(base) + INDEX)
    os.environ["FTT_ROS_DOMAIN_ID"] = os.environ["ROS_DOMAIN_ID"] = domain
    if os.environ.get("FTT_TEST_REDIS_URL"):
        os.environ["FTT_TEST_REDIS_URL"] = redis_url(os.environ["FTT_TEST_REDIS_URL"])
