"""The transform tree: frames, their parents, and a short stamped history per edge.

tf2's model, kept small: every frame has at most one parent (a new parent replaces the old
edge, as tf2 does); each edge keeps the samples of the last ``cache_time`` seconds, sorted by
stamp; static edges keep one sample valid at every time. A lookup walks the tree path between
two frames (networkx) and composes the edge transforms, each interpolated at the asked time.
Time 0 means "the latest time every edge on the path has data for", the tutorial's
``rospy.Time(0)``.

Pure: no topics, no clocks. Times are float seconds; the listener converts.
"""
from __future__ import annotations

import bisect
import threading
from dataclasses import dataclass, field

import networkx as nx

from orchestra.tf import transformations as tfm
from orchestra.tf.transformations import Transform


class TransformException(Exception):
    """Base of every lookup failure (tf.Exception / tf2.TransformException)."""


class LookupException(TransformException):
    """A frame nobody has published."""


class ConnectivityException(TransformException):
    """Both frames exist but belong to different trees."""


class ExtrapolationException(TransformException):
    """The asked time is outside the stored history of an edge on the path."""


def strip_frame(frame_id: str) -> str:
    """tf2 ignores a leading slash ('/turtle1' is 'turtle1'); tf1 code still sends one."""
    return frame_id[1:] if frame_id.startswith("/") else frame_id


@dataclass
class _Edge:
    """Child frame's pose in its parent over time."""

    parent: str
    static: bool = False
    stamps: list[float] = field(default_factory=list)
    samples: list[Transform] = field(default_factory=list)

    def insert(self, stamp: float, transform: Transform, cache_time: float) -> None:
        if self.static:
            self.stamps, self.samples = [stamp], [transform]
            return
        i = bisect.bisect_left(self.stamps, stamp)
        if i < len(self.stamps) and self.stamps[i] == stamp:
            self.samples[i] = transform
        else:
            self.stamps.insert(i, stamp)
            self.samples.insert(i, transform)
        # forget what is older than cache_time behind the newest sample
        cutoff = self.stamps[-1] - cache_time
        drop = bisect.bisect_left(self.stamps, cutoff)
        if drop:
            del self.stamps[:drop]
            del self.samples[:drop]

    def latest(self) -> float:
        return self.stamps[-1]

    def at(self, stamp: float, tolerance: float) -> Transform:
        """The sample at ``stamp``, interpolated between neighbours; a stamp outside the history by
        more than ``tolerance`` seconds is an extrapolation error."""
        if self.static:
            return self.samples[0]
        first, last = self.stamps[0], self.stamps[-1]
        if stamp <= first:
            if first - stamp > tolerance:
                raise ExtrapolationException(
                    f"lookup would require extrapolation into the past: requested {stamp:.3f} "
                    f"but the earliest data is at {first:.3f}")
            return self.samples[0]
        if stamp >= last:
            if stamp - last > tolerance:
                raise ExtrapolationException(
                    f"lookup would require extrapolation into the future: requested {stamp:.3f} "
                    f"but the latest data is at {last:.3f}")
            return self.samples[-1]
        i = bisect.bisect_right(self.stamps, stamp)
        t0, t1 = self.stamps[i - 1], self.stamps[i]
        return tfm.interpolate(self.samples[i - 1], self.samples[i], (stamp - t0) / (t1 - t0))


class TransformBuffer:
    """Thread-safe frame tree: ``set_transform`` from a receive thread, ``lookup`` from anywhere."""

    def __init__(self, cache_time: float = 10.0, tolerance: float = 0.0):
        self.cache_time = cache_time
        # a small default tolerance would hide real timing bugs; tf's is zero too
        self.tolerance = tolerance
        self._edges: dict[str, _Edge] = {}  # child -> edge to its parent
        self._graph = nx.Graph()
        self._lock = threading.Condition()

    # --- writing -----------------------------------------------------------------------------

    def set_transform(self, parent: str, child: str, stamp: float, transform: Transform,
                      static: bool = False) -> None:
        parent, child = strip_frame(parent), strip_frame(child)
        if not parent or not child:
            raise ValueError("frame ids must not be empty")
        if parent == child:
            raise ValueError(f"frame '{child}' cannot be its own parent")
        trans, rot = transform
        transform = (tuple(float(c) for c in trans), tfm.normalize(rot))  # type: ignore[assignment]
        with self._lock:
            edge = self._edges.get(child)
            if edge is None or edge.parent != parent or edge.static != static:
                if edge is not None:
                    self._graph.remove_edge(child, edge.parent)
                edge = _Edge(parent=parent, static=static)
                self._edges[child] = edge
                self._graph.add_edge(child, parent)
            edge.insert(float(stamp), transform, self.cache_time)
            self._lock.notify_all()

    def clear(self) -> None:
        """Forget every transform (tf's ``clear``, e.g. after the clock jumped back)."""
        with self._lock:
            self._edges.clear()
            self._graph.clear()

    # --- reading -----------------------------------------------------------------------------

    def frames(self) -> list[str]:
        with self._lock:
            return sorted(self._graph.nodes)

    def parents(self) -> dict[str, str]:
        """child -> parent for every edge: the tree as view_frames draws it."""
        with self._lock:
            return {child: edge.parent for child, edge in self._edges.items()}

    def edge_info(self) -> dict[str, dict]:
        """Per child frame: parent, static, sample count, oldest/newest stamp."""
        with self._lock:
            return {child: {"parent": e.parent, "static": e.static, "samples": len(e.stamps),
                            "oldest": e.stamps[0], "newest": e.stamps[-1]}
                    for child, e in self._edges.items()}

    def _path(self, target: str, source: str) -> list[str]:
        for frame in (target, source):
            if frame not in self._graph:
                raise LookupException(f'"{frame}" passed to lookup_transform argument '
                                      f'{"target_frame" if frame == target else "source_frame"} '
                                      "does not exist")
        try:
            return nx.shortest_path(self._graph, target, source)
        except nx.NetworkXNoPath:
            raise ConnectivityException(
                f'could not find a connection between "{target}" and "{source}" because they '
                "are not part of the same tree") from None

    def _latest_common_time(self, path: list[str]) -> float:
        latest = None
        for a, b in zip(path, path[1:], strict=False):
            edge = self._edges[a] if a in self._edges and self._edges[a].parent == b \
                else self._edges[b]
            if edge.static:
                continue
            latest = edge.latest() if latest is None else min(latest, edge.latest())
        return 0.0 if latest is None else latest

    def lookup(self, target: str, source: str, stamp: float = 0.0) -> tuple[Transform, float]:
        """Pose of frame ``source`` in frame ``target`` at ``stamp`` (0 = latest common time),
        with the stamp actually used. Maps points given in ``source`` into ``target``."""
        target, source = strip_frame(target), strip_frame(source)
        with self._lock:
            if target == source:
                if target not in self._graph:
                    raise LookupException(f'"{target}" does not exist')
                return tfm.IDENTITY, stamp
            path = self._path(target, source)
            if not stamp:
                stamp = self._latest_common_time(path)
            result = tfm.IDENTITY
            for a, b in zip(path, path[1:], strict=False):
                up = self._edges.get(b)
                if up is not None and up.parent == a:  # a is b's parent: b's pose in a
                    step = up.at(stamp, self.tolerance)
                else:  # b is a's parent: invert a's pose in b
                    step = tfm.inverse(self._edges[a].at(stamp, self.tolerance))
                result = tfm.compose(result, step)
            return result, stamp

    def can_transform(self, target: str, source: str, stamp: float = 0.0) -> bool:
        try:
            self.lookup(target, source, stamp)
        except TransformException:
            return False
        return True

    def wait_for_transform(self, target: str, source: str, stamp: float, timeout: float,
                           is_shutdown=lambda: False) -> Transform:
        """Block until the lookup succeeds (new data wakes us) or ``timeout`` seconds pass; then
        the last lookup error is raised."""
        import time as _time
        deadline = _time.monotonic() + timeout
        with self._lock:
            while True:
                try:
                    return self.lookup(target, source, stamp)[0]
                except TransformException:
                    remaining = deadline - _time.monotonic()
                    if remaining <= 0 or is_shutdown():
                        raise
                    self._lock.wait(min(remaining, 0.1))
