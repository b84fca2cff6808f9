"""A small TF buffer: tf2_ros has no wheel, and the collector needs one lookup.

It keeps, per child frame, its parent and either one static transform or a
short time-sorted history.  :meth:`TfBuffer.lookup` chains the transforms
between two frames through their common ancestor, interpolating each edge at
the requested time (linear for translations, slerp for rotations).  Without a
time it uses the latest time every edge of the chain can answer, like tf2's
"time zero".
"""

import bisect
import math
from collections import deque
from dataclasses import dataclass

Vec = tuple[float, float, float]
Quat = tuple[float, float, float, float]  # x, y, z, w


@dataclass(frozen=True)
class Transform:
    translation: Vec
    rotation: Quat
    stamp_ns: int | None = None

    @property
    def yaw(self) -> float:
        return yaw_of(self.rotation)


def yaw_of(q: Quat) -> float:
    x, y, z, w = q
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def _qmul(a: Quat, b: Quat) -> Quat:
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _qconj(q: Quat) -> Quat:
    return (-q[0], -q[1], -q[2], q[3])


def _rotate(q: Quat, v: Vec) -> Vec:
    x, y, z, _ = _qmul(_qmul(q, (v[0], v[1], v[2], 0.0)), _qconj(q))
    return (x, y, z)


def _normalise(q: Quat) -> Quat:
    n = math.sqrt(sum(c * c for c in q))
    if not math.isfinite(n) or n < 1e-12:
        raise ValueError("degenerate quaternion")
    return tuple(c / n for c in q)  # type: ignore[return-value]


def compose(a: Transform, b: Transform) -> Transform:
    """a ∘ b: b expressed in a's parent frame."""
    t = _rotate(a.rotation, b.translation)
    return Transform(
        (a.translation[0] + t[0], a.translation[1] + t[1], a.translation[2] + t[2]),
        _normalise(_qmul(a.rotation, b.rotation)),
    )


def invert(a: Transform) -> Transform:
    q = _qconj(a.rotation)
    t = _rotate(q, a.translation)
    return Transform((-t[0], -t[1], -t[2]), q)


IDENTITY = Transform((0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def _slerp(a: Quat, b: Quat, f: float) -> Quat:
    dot = sum(x * y for x, y in zip(a, b, strict=True))
    if dot < 0.0:
        b, dot = tuple(-c for c in b), -dot  # type: ignore[assignment]
    if dot > 0.9995:
        return _normalise(tuple(x + f * (y - x) for x, y in zip(a, b, strict=True)))
    theta = math.acos(dot)
    s = math.sin(theta)
    wa, wb = math.sin((1 - f) * theta) / s, math.sin(f * theta) / s
    return _normalise(tuple(wa * x + wb * y for x, y in zip(a, b, strict=True)))


class TfLookupError(LookupError):
    pass


class _Edge:
    def __init__(self, parent: str, history: float):
        self.parent = parent
        self.static: Transform | None = None
        self.stamps: deque[int] = deque()
        self.values: deque[Transform] = deque()
        self.history_ns = int(history * 1e9)

    def add(self, tf: Transform) -> None:
        stamp = tf.stamp_ns or 0
        if self.stamps and stamp < self.stamps[-1]:
            # Out of order (or a restarted clock): keep the history sorted.
            i = bisect.bisect_left(list(self.stamps), stamp)
            self.stamps.insert(i, stamp)
            self.values.insert(i, tf)
        else:
            self.stamps.append(stamp)
            self.values.append(tf)
        while self.stamps and self.stamps[-1] - self.stamps[0] > self.history_ns:
            self.stamps.popleft()
            self.values.popleft()

    def latest(self) -> int | None:
        return None if self.static is not None else (self.stamps[-1] if self.stamps else None)

    def at(self, stamp_ns: int, tolerance_ns: int) -> Transform:
        if self.static is not None:
            return self.static
        if not self.stamps:
            raise TfLookupError("no data")
        stamps = self.stamps
        if stamp_ns >= stamps[-1]:
            if stamp_ns - stamps[-1] > tolerance_ns:
                raise TfLookupError("would extrapolate into the future")
            return self.values[-1]
        if stamp_ns <= stamps[0]:
            if stamps[0] - stamp_ns > tolerance_ns:
                raise TfLookupError("older than the buffer")
            return self.values[0]
        i = bisect.bisect_right(stamps, stamp_ns)
        t0, t1 = stamps[i - 1], stamps[i]
        a, b = self.values[i - 1], self.values[i]
        f = (stamp_ns - t0) / (t1 - t0) if t1 > t0 else 0.0
        return Transform(
            tuple(x + f * (y - x) for x, y in zip(a.translation, b.translation, strict=True)),
            _slerp(a.rotation, b.rotation, f),
        )


class TfBuffer:
    def __init__(self, history: float = 10.0, tolerance: float = 0.0):
        self._edges: dict[str, _Edge] = {}
        self.history = history
        self.tolerance_ns = int(tolerance * 1e9)

    def clear(self) -> None:
        self._edges.clear()

    def set_transform(
        self, parent: str, child: str, transform: Transform, static: bool = False
    ) -> None:
        parent, child = parent.lstrip("/"), child.lstrip("/")
        if not parent or not child or parent == child:
            raise ValueError("a transform needs two different frame names")
        values = (*transform.translation, *transform.rotation)
        if not all(math.isfinite(v) for v in values):
            raise ValueError("non-finite transform")
        transform = Transform(
            transform.translation, _normalise(transform.rotation), transform.stamp_ns
        )
        edge = self._edges.get(child)
        if edge is None or edge.parent != parent:
            # A frame re-parented (or new): its old history no longer applies.
            edge = self._edges[child] = _Edge(parent, self.history)
        if static:
            edge.static = transform
        else:
            edge.static = None
            edge.add(transform)

    def _path_to_root(self, frame: str) -> list[str]:
        path = [frame]
        seen = {frame}
        while (edge := self._edges.get(path[-1])) is not None:
            if edge.parent in seen:
                raise TfLookupError("loop in the TF tree")
            path.append(edge.parent)
            seen.add(edge.parent)
        return path

    def _chain(self, target: str, source: str) -> tuple[list[str], list[str]]:
        up_source = self._path_to_root(source)
        up_target = self._path_to_root(target)
        common = next((f for f in up_source if f in set(up_target)), None)
        if common is None:
            raise TfLookupError(f"'{target}' and '{source}' are not connected")
        return (
            up_source[: up_source.index(common)],
            up_target[: up_target.index(common)],
        )

    def lookup(self, target: str, source: str, stamp_ns: int | None = None) -> Transform:
        """Pose of ``source`` in ``target`` (tf2's lookupTransform(target, source))."""
        target, source = target.lstrip("/"), source.lstrip("/")
        if target == source:
            return Transform(IDENTITY.translation, IDENTITY.rotation, stamp_ns)
        from_source, from_target = self._chain(target, source)
        edges = [self._edges[f] for f in from_source + from_target]
        if stamp_ns is None:
            latest = [s for e in edges if (s := e.latest()) is not None]
            if len(latest) < sum(1 for e in edges if e.static is None):
                raise TfLookupError("no data on part of the chain")
            stamp_ns = min(latest) if latest else 0
        source_in_common = IDENTITY
        for frame in from_source:  # walk upwards: parent_T_child ∘ ...
            source_in_common = compose(
                self._edges[frame].at(stamp_ns, self.tolerance_ns), source_in_common
            )
        target_in_common = IDENTITY
        for frame in from_target:
            target_in_common = compose(
                self._edges[frame].at(stamp_ns, self.tolerance_ns), target_in_common
            )
        result = compose(invert(target_in_common), source_in_common)
        return Transform(result.translation, result.rotation, stamp_ns)
