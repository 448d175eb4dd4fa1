"""What a controller shows of its thinking, as plain data: the controller host turns each into a message
(``closed_loop.nodes.drawing_messages``) and publishes it on the controller's private topic of that name
(``~window``, ``~plan``, ``~map``, ``~tracks``, ``~belief``, ``~goal``), and an episode can keep it. Free of
ROS.

A controller declares its outputs once, as {name: kind} with kinds :class:`Drawing` (an rviz
MarkerArray), :class:`Note` (a JSON text on std_msgs/String), :class:`Goal` (a latched
geometry_msgs/PoseStamped in odom) and :class:`Route` (a nav_msgs/Path in odom), and after each decision
returns those that have news.
"""
import dataclasses
from typing import Optional, Tuple

#: Frames a drawing may be in: the robot's base (it moves with the robot) or odometry's fixed frame.
FRAMES = ('base', 'odom')
#: rviz marker kinds a shape may take.
KINDS = ('line', 'points', 'sphere', 'cylinder', 'arrow')


def _one_of(name, value, allowed):
    if value not in allowed:
        raise ValueError('%s: expected one of %s, got %r' % (name, ', '.join(allowed), value))


@dataclasses.dataclass(frozen=True)
class Shape:
    """One marker. ``kind``: one of :data:`KINDS`; ``ns`` and ``id`` name it in rviz. ``points``: (x, y, z) m
    for a line, points or an arrow (start, end); ``position``: (x, y, z) m for a sphere or a cylinder;
    ``scale``: (x, y, z) as rviz reads it for the kind (a line's width is x); ``colour``: (r, g, b, a) in 0..1;
    ``colours``: one colour per point (points only)."""
    kind: str
    ns: str
    id: int
    colour: Tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0)
    scale: Tuple[float, float, float] = (0.1, 0.1, 0.1)
    points: tuple = ()
    position: Tuple[float, float, float] = (0.0, 0.0, 0.0)
    colours: tuple = ()

    def __post_init__(self):
        _one_of('kind', self.kind, KINDS)


@dataclasses.dataclass(frozen=True)
class Drawing:
    """Shapes in one frame (:data:`FRAMES`); ``clear``: delete what was drawn before on this topic first."""
    frame: str
    shapes: tuple = ()
    clear: bool = False

    def __post_init__(self):
        _one_of('frame', self.frame, FRAMES)


@dataclasses.dataclass(frozen=True)
class Note:
    """Plain values (numbers, strings, lists, mappings) for a JSON text."""
    data: dict


@dataclasses.dataclass(frozen=True)
class Goal:
    """The goal being followed, (x, y) m in odom; None: none (holding a heading)."""
    xy: Optional[Tuple[float, float]]


@dataclasses.dataclass(frozen=True)
class Route:
    """A way to follow, as (x, y) m points in odom from the robot onwards (a nav_msgs/Path); () for none."""
    points: tuple = ()

