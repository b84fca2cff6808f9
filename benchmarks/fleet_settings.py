"""Settings of the server and collectors benchmarks/fleet.py starts: production's,
with the live link's and the collector's timings of each mode switch logged
(DEBUG), from which the benchmark splits a switch's way to the screen."""

from ftt_site.settings import *  # noqa: F403

LOGGING["loggers"] |= {  # noqa: F405
    "live.consumers": {"level": "DEBUG"},
    "ftt.collector": {"level": "DEBUG"},
}
