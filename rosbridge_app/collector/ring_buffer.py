"""The black box's memory: the last seconds of raw messages, bounded by age and size."""

from collections import deque


class RingBuffer:
    """(receive time ns, topic, bytes), bounded by age and by total size; the
    oldest go first and ``dropped`` counts the messages dropped for size."""

    def __init__(self, seconds: float, max_bytes: int):
        self.seconds, self.max_bytes = seconds, max_bytes
        self.items: deque = deque()
        self.size = 0
        self.dropped = 0

    def add(self, t_ns: int, topic: str, data: bytes) -> None:
        self.items.append((t_ns, topic, data))
        self.size += len(data)
        oldest = t_ns - int(self.seconds * 1e9)
        items = self.items
        while items and (items[0][0] < oldest or self.size > self.max_bytes):
            if items[0][0] >= oldest:
                self.dropped += 1
            self.size -= len(items.popleft()[2])

    def since(self, t_ns: int) -> list:
        return [item for item in self.items if item[0] >= t_ns]
