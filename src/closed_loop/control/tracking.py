"""Obstacles as tracks: clusters of scan points in odom, followed from scan to scan, each with a position, a
velocity and an age, and "moving" when it has moved faster than a threshold over a window. For the fusion
controller (lesson exercise 3). Free of ROS.

**Clustering rule** (adaptive breakpoints, as Dietmayer et al. 2001 and most 2D LIDAR trackers): the scan's
valid returns, in ray order, are cut where two consecutive returns lie farther apart than
``cluster_gap`` or ``GAP_RAYS`` times the arc one ray increment spans at that range, whichever is larger
(a far object's points are farther apart, not separate), or where a ray between them had no valid return.
A full turn's first and last runs join when they meet. A cluster has at least ``min_points`` returns; its
position is the mean of its points, in odom (the robot's pose at the scan), and its size is the largest
distance between two of its points.

**Tracks:** each cluster of at most ``max_size`` (a person, a post, a box; a wall is longer and is never
tracked as one thing, since the part of it the LIDAR sees slides as the robot moves) is matched to the
nearest track whose predicted position (last position plus velocity times the time since) is within
``gate`` of it, nearest pairs first; a cluster with no track starts one; a track unseen for
``track_timeout`` is dropped. A track's velocity is the slope of a least-squares line through its positions
of the last ``window_s``; it is **moving** once its history spans at least ``window_s`` and its speed is
above ``moving_speed``. Because tracks live in odom, the robot's own motion does not make a still object
move.
"""
import dataclasses
import math

import numpy

from closed_loop.control.scan import sample_angles, usable_ranges
from closed_loop.settings import param

#: A gap of this many ray-arcs at the range of the returns is still one object.
GAP_RAYS = 3.0


@dataclasses.dataclass
class TrackerSettings:
    """The tracker's ``~parameters`` (the fusion controller's)."""
    cluster_gap: float = param(0.15, 'm', 'neighbouring returns farther apart than this (or than 3 ray-arcs '
                               'at their range) start a new cluster', minimum=0.01, maximum=2.0)
    min_points: int = param(3, '', 'a cluster has at least this many returns', minimum=1, maximum=100)
    max_size: float = param(1.0, 'm', 'clusters larger than this (walls) are not tracked as objects',
                            minimum=0.1, maximum=10.0)
    gate: float = param(0.5, 'm', 'a cluster joins the track predicted nearest to it within this', minimum=0.05,
                        maximum=5.0)
    window_s: float = param(1.0, 's', 'velocity is fitted over this much of a track\'s history',
                            minimum=0.2, maximum=10.0)
    moving_speed: float = param(0.3, 'm/s', 'a track faster than this over the window is moving',
                                minimum=0.0, exclusive_minimum=True)
    track_timeout: float = param(1.0, 's', 'a track unseen this long is dropped', minimum=0.1, maximum=30.0,
                                )


@dataclasses.dataclass(frozen=True)
class Cluster:
    """One cluster of a scan: its position (x, y) and points ((N, 2)) in odom, its size (m), and its
    first and last ray's indices."""
    x: float
    y: float
    size: float
    points: numpy.ndarray
    first_ray: int
    last_ray: int


def clusters(scan, laser_pose, robot_pose, settings):
    """The scan's clusters (:class:`Cluster`), in odom. ``laser_pose``: the laser in the base frame
    (``geometry.Pose2D``); ``robot_pose``: (x, y, yaw) of the base in odom at the scan."""
    ranges = usable_ranges(scan)
    angles = sample_angles(scan) + laser_pose.yaw
    valid = numpy.isfinite(ranges)
    # -inf (closer than range_min) is a return at range_min, as for the other consumers of a scan.
    r = numpy.where(valid, ranges, numpy.nan)
    bx = laser_pose.x + r * numpy.cos(angles)
    by = laser_pose.y + r * numpy.sin(angles)
    x, y, yaw = robot_pose
    c, s = math.cos(yaw), math.sin(yaw)
    px, py = x + c * bx - s * by, y + s * bx + c * by
    n = len(r)
    if n == 0 or not valid.any():
        return []
    step = abs(scan.angle_increment)
    gap = numpy.hypot(numpy.diff(px), numpy.diff(py))
    limit = numpy.maximum(settings.cluster_gap, GAP_RAYS * step * numpy.fmax(r[:-1], r[1:]))
    joined = valid[:-1] & valid[1:] & (gap <= limit)          # ray i and i+1 in one cluster
    runs, start = [], None
    for i in range(n):
        if valid[i] and start is None:
            start = i
        if start is not None and (i == n - 1 or not joined[i]):
            runs.append([start, i])
            start = None
    full_turn = scan.angle_max - scan.angle_min + step >= 2 * math.pi - 1e-6
    if full_turn and len(runs) > 1 and runs[0][0] == 0 and runs[-1][1] == n - 1 and valid[0] and valid[-1] \
            and math.hypot(px[0] - px[-1], py[0] - py[-1]) <= max(settings.cluster_gap,
                                                                 GAP_RAYS * step * max(r[0], r[-1])):
        runs[0][0] = runs[-1][0] - n                          # the last run continues into the first
        runs.pop()
    out = []
    for first, last in runs:
        index = numpy.arange(first, last + 1) % n
        if len(index) < settings.min_points:
            continue
        points = numpy.column_stack((px[index], py[index]))
        d = points[:, None, :] - points[None, :, :]
        size = float(numpy.sqrt((d * d).sum(axis=2).max())) if len(points) <= 400 else \
            float(numpy.hypot(*(points.max(axis=0) - points.min(axis=0))))
        centre = points.mean(axis=0)
        out.append(Cluster(float(centre[0]), float(centre[1]), size, points, int(index[0]), int(index[-1])))
    return out


@dataclasses.dataclass
class Track:
    """One object followed over time: ``id``, position and velocity in odom, ``born_s`` and ``seen_s``
    (times), its recent history [(t, x, y)], its size, and ``moving``."""
    id: int
    x: float
    y: float
    vx: float
    vy: float
    born_s: float
    seen_s: float
    size: float
    history: list
    moving: bool = False

    @property
    def speed(self):
        return math.hypot(self.vx, self.vy)

    def age_s(self, now_s):
        return now_s - self.born_s

    def predicted(self, now_s):
        dt = max(0.0, now_s - self.seen_s)
        return self.x + self.vx * dt, self.y + self.vy * dt


class Tracker:
    """Tracks from scan to scan (see the module's docstring). :meth:`update` with each scan's clusters."""

    def __init__(self, settings):
        self.settings = settings
        self.tracks = []
        self._next_id = 1

    def update(self, now_s, found):
        """Advance to ``now_s`` with the clusters ``found`` (:func:`clusters`); returns the live tracks."""
        s = self.settings
        objects = [c for c in found if c.size <= s.max_size]
        pairs = []
        for ti, track in enumerate(self.tracks):
            px, py = track.predicted(now_s)
            for ci, cluster in enumerate(objects):
                d = math.hypot(cluster.x - px, cluster.y - py)
                if d <= s.gate:
                    pairs.append((d, ti, ci))
        pairs.sort()
        used_tracks, used_clusters = set(), set()
        for _, ti, ci in pairs:
            if ti in used_tracks or ci in used_clusters:
                continue
            used_tracks.add(ti)
            used_clusters.add(ci)
            self._observe(self.tracks[ti], now_s, objects[ci])
        for ci, cluster in enumerate(objects):
            if ci not in used_clusters:
                self.tracks.append(Track(self._next_id, cluster.x, cluster.y, 0.0, 0.0, now_s, now_s, cluster.size,
                                         [(now_s, cluster.x, cluster.y)]))
                self._next_id += 1
        self.tracks = [t for t in self.tracks if now_s - t.seen_s <= s.track_timeout]
        return list(self.tracks)

    def _observe(self, track, now_s, cluster):
        s = self.settings
        track.x, track.y, track.seen_s, track.size = cluster.x, cluster.y, now_s, cluster.size
        track.history.append((now_s, cluster.x, cluster.y))
        track.history = [h for h in track.history if now_s - h[0] <= s.window_s + 1e-9]
        t = numpy.array([h[0] for h in track.history])
        if len(t) >= 2 and t[-1] > t[0]:
            tc = t - t.mean()
            denom = float((tc * tc).sum())
            track.vx = float((tc * numpy.array([h[1] for h in track.history])).sum() / denom)
            track.vy = float((tc * numpy.array([h[2] for h in track.history])).sum() / denom)
        spans = now_s - track.born_s >= s.window_s - 1e-9
        track.moving = bool(spans and track.speed > s.moving_speed)
