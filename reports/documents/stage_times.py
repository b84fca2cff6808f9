"""Wall and CPU seconds per stage of making a report (statistics, maps, charts,
timelines, image encoding, typesetting): ``ftt_report -v 2`` prints them, so an
administrator can see where a slow report spends its time."""

import time
from collections import defaultdict
from contextlib import contextmanager


class StageTimes:
    """Seconds per stage, summed over every time a stage ran. CPU seconds (all
    threads of this process) vary far less with the machine's load than wall
    seconds."""

    def __init__(self):
        self.wall: dict[str, float] = defaultdict(float)
        self.cpu: dict[str, float] = defaultdict(float)

    @contextmanager
    def timed(self, stage: str):
        wall, cpu = time.perf_counter(), time.process_time()
        try:
            yield
        finally:
            self.wall[stage] += time.perf_counter() - wall
            self.cpu[stage] += time.process_time() - cpu

    def rows(self) -> list[tuple[str, float, float]]:
        """(stage, wall seconds, CPU seconds), in the order the stages first ran."""
        return [(stage, wall, self.cpu[stage]) for stage, wall in self.wall.items()]
