"""Where a world's obstacles are and what they cover: footprint overlaps (the start checks), the paths of
moving obstacles over time, and the static ones grouped by area (the simulator's compound bodies). Free of ROS
and pybullet; obstacles are :class:`closed_loop.sim.world.Obstacle`.
"""
import functools
import math

from closed_loop.sim import shapes


def disk_overlaps(obstacle, x_m, y_m, radius_m):
    """True if a disk (centre ``x_m``, ``y_m``, radius ``radius_m``, in m) overlaps the footprint.

    The footprint is the obstacle's shape seen from above at its time-0 position: a rotated
    rectangle for a box, a disk for a cylinder (:mod:`closed_loop.sim.shapes`). Height is ignored.
    Touching (distance exactly equal to the radius) is not an overlap.
    """
    return shapes.distance(obstacle, x_m, y_m) < radius_m


def footprint_overlaps(obstacle, pose, footprint, margin_m=0.0):
    """True if the robot's footprint rectangle at ``pose`` (a Pose2D), grown by ``margin_m``, overlaps the
    obstacle's footprint at its time-0 position. Touching is not an overlap."""
    rect = (footprint.x_min - margin_m, footprint.x_max + margin_m,
            footprint.y_min - margin_m, footprint.y_max + margin_m)
    return shapes.SHAPES[obstacle.shape].overlaps_robot(obstacle, pose, rect)


# The simulator asks for a moving obstacle's place every physics step; its path never changes.
@functools.lru_cache(maxsize=256)
def motion_path(obstacle):
    """The closed or back-and-forth path of a moving obstacle as ``(points, cycle_length_m)``.

    ``points`` are the (x, y) corners visited in one cycle, first and last equal to the start
    position; consecutive duplicates are dropped. For ``loop`` the cycle is start -> waypoints ->
    start; for ping-pong it is start -> waypoints -> back the same way to start.
    """
    motion = obstacle.motion
    start = (obstacle.position[0], obstacle.position[1])
    forward = [start] + list(motion.waypoints)
    if motion.loop:
        corners = forward + [start]
    else:
        corners = forward + forward[-2::-1]
    points = [corners[0]]
    for point in corners[1:]:
        if point != points[-1]:
            points.append(point)
    length = sum(math.hypot(b[0] - a[0], b[1] - a[1]) for a, b in zip(points, points[1:]))
    return points, length


def moving_obstacle_xy(obstacle, t_s):
    """Where ``obstacle``'s centre is (x, y in m) at time ``t_s`` (s, >= 0) since the world started.

    The obstacle moves at constant speed along :func:`motion_path` and repeats it forever. A
    static obstacle returns its own x, y. Raises ValueError if ``t_s`` is negative or not finite.
    """
    if isinstance(t_s, bool) or not isinstance(t_s, (int, float)) or not math.isfinite(t_s) \
            or t_s < 0.0:
        raise ValueError('t_s: expected a finite time >= 0 s, got %r' % (t_s,))
    if obstacle.motion is None:
        return obstacle.position[0], obstacle.position[1]
    points, cycle_m = motion_path(obstacle)
    return point_on_path(points, cycle_m, obstacle.motion.speed * t_s)


def point_on_path(points, cycle_m, distance_m):
    """The (x, y) reached after ``distance_m`` along a :func:`motion_path` cycle, repeating it forever."""
    if not cycle_m > 0.0:
        return points[0]
    travelled = math.fmod(distance_m, cycle_m)
    for a, b in zip(points, points[1:]):
        segment = math.hypot(b[0] - a[0], b[1] - a[1])
        if travelled <= segment:
            f = travelled / segment
            return a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])
        travelled -= segment
    # Rounding can leave a sliver past the last corner; the path ends where it began.
    return points[-1]


#: A static obstacle whose bounding circle is wider than this (m; a wall) is grouped with its kind, not among
#: the small ones round it, whose patches its centre would stretch.
LARGE_M = 1.0


def static_groups(obstacles, most):
    """The static obstacles of ``obstacles`` in groups of at most ``most``, each a compact patch of the world: the
    patch split at the median of its centres along its longer side until each part is small enough; the large
    ones (LARGE_M) are split so among themselves."""
    def split(group):
        if len(group) <= most:
            return [group]
        xs = [o.position[0] for o in group]
        ys = [o.position[1] for o in group]
        axis = 0 if max(xs) - min(xs) >= max(ys) - min(ys) else 1
        ordered = sorted(group, key=lambda o: (o.position[axis], o.position[1 - axis], o.name))
        half = len(ordered) // 2
        return split(ordered[:half]) + split(ordered[half:])
    static = [o for o in obstacles if o.motion is None]
    large = [o for o in static if shapes.bounding_radius(o) > LARGE_M]
    small = [o for o in static if shapes.bounding_radius(o) <= LARGE_M]
    return [group for part in (small, large) if part for group in split(part)]
