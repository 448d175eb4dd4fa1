"""A picture of an episode, top-down (matplotlib, PNG), to see why it failed before reading about it.

It shows the obstacles in their shapes and colours (a moving one along its dashed path, where it was at the
start, faint, and at the end), the start and the goal with its success radius, the path coloured by the
controller's mode (or by speed, for a controller without modes), the robot's footprint at the start, at the
end and where it came closest to an obstacle, every contact (a red cross where the robot was, the obstacle
it touched outlined in red), and a title line with the outcome, the time, the least clearance and the
contacts. Drawn from an episode's track (``keep_trajectory``: ``closed_loop.batch.judge.TRACK_FIELDS`` and
the contact log), in process or from a graph episode's judge alike. Free of ROS.

Which episodes a sweep draws: ``report: {pictures: failures}`` (the default) those whose outcome is not
what they were for (:func:`is_failure`), ``all`` every one, ``none`` none; at most ``max_pictures``
(``closed_loop.batch.sweep_file``), the rest on request (``rosrun closed_loop episode_plot OUTPUT INDEX``).
"""
import io
import math

from closed_loop.sim import obstacles as obstacle_paths
from closed_loop.sim import shapes

CHOICES = ('failures', 'all', 'none')
#: Outcomes that are failures whatever the controller (a stop controller's ``stopped`` and a navigator's
#: ``reached`` are what they are for; any contact is a failure too).
FAILING = ('collided', 'failed', 'timed_out', 'error')
#: A mode's colour on the path (others take the next of PALETTE).
MODE_COLOURS = {'CLEAR': '#2ca02c', 'GOAL_SEEKING': '#2ca02c', 'EXPLORING': '#2ca02c', 'SLOW': '#ff7f0e',
                'AVOIDING': '#ff7f0e', 'WAITING': '#ff7f0e', 'STOP': '#d62728', 'BACKING_UP': '#d62728',
                'RECOVERING': '#9467bd', 'REACHED': '#1f77b4', 'FAILED': '#7f0000'}
PALETTE = ('#9467bd', '#8c564b', '#e377c2', '#17becf', '#bcbd22', '#7f7f7f', '#1f77b4', '#aec7e8')
#: How far (m) beyond the path, the start and the goal the picture reaches.
MARGIN_M = 1.5
SIZE_IN, DPI = (8.0, 6.4), 100


def is_failure(outcome, contacts):
    """True if an episode did not do what it was for: collided, failed, timed out or could not run, or
    touched anything (a stop controller's contact that still ended 'stopped')."""
    try:
        touched = int(contacts or 0) > 0
    except (TypeError, ValueError):
        touched = False
    return outcome in FAILING or touched


def wanted(choice, outcome, contacts):
    """Whether a sweep with ``report.pictures`` = ``choice`` draws this episode."""
    return choice == 'all' or (choice == 'failures' and is_failure(outcome, contacts))


def title(result, label=''):
    """The picture's title line: what happened, when, how close, how many contacts."""
    clearance = result.min_clearance_m
    text = '%s after %.1f s: least clearance %s, %d contact%s' % (
        result.outcome, result.time_s, '%.3f m' % clearance if math.isfinite(clearance) else 'over the lookout',
        result.contacts, '' if result.contacts == 1 else 's')
    return '%s: %s' % (label, text) if label else text


def episode_picture(spec, result, cache=None, label='', colour_by=None):
    """The PNG of episode ``spec`` (an ``EpisodeSpec``) that gave ``result`` (its trajectory kept), labelled
    ``label`` and what ran: the controller, the robot and the world."""
    from closed_loop.batch.episode import SUCCESS_RADIUS_M, prepare
    p = prepare(spec, cache)
    controller = spec.controller if isinstance(spec.controller, str) else (
        spec.controller.get('launch') or spec.controller.get('node'))
    what = '%s, %s in %s' % (controller, spec.robot, p.world.name)
    return draw(result, p.world, p.profile.footprint, p.goal_world, SUCCESS_RADIUS_M,
                '%s (%s)' % (label, what) if label else what, colour_by)


def draw(result, world, footprint, goal=None, success_radius=None, label='', colour_by=None):
    """The PNG (bytes) of ``result`` (an ``EpisodeResult`` with its trajectory and contact log) in ``world``
    (a ``closed_loop.sim.world.World``), the robot's ``footprint`` (``closed_loop.robot_model.Footprint``),
    the goal (x, y) in the world frame and its success radius (m). ``colour_by``: 'mode' or 'speed'
    (default: mode where the controller has modes)."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon

    rows = list(result.trajectory or [])
    contacts = list(result.contact_log or [])
    start = world.robot_start
    end_t = rows[-1][0] if rows else 0.0
    (x0, x1), (y0, y1) = _limits(rows, start, goal)
    height = min(max(SIZE_IN[0] * (y1 - y0) / (x1 - x0) + 1.0, 4.0), SIZE_IN[1] * 1.4)
    figure, axes = pyplot.subplots(figsize=(SIZE_IN[0], height))
    axes.set_aspect('equal')
    axes.set_xlim(x0, x1)
    axes.set_ylim(y0, y1)
    axes.set_facecolor('#f4f4f0')
    # The obstacles: static ones as they are; a moving one faint at the start, solid where it was at the end.
    touched = {name for row in contacts for name in row[4]}
    polygons, faces, edges, widths = [], [], [], []
    for o in world.obstacles:
        colour = tuple(o.color[:3]) + (max(o.color[3], 0.75),)
        x, y = obstacle_paths.moving_obstacle_xy(o, end_t)
        if o.motion is not None:
            points, _ = obstacle_paths.motion_path(o)
            axes.plot([p[0] for p in points], [p[1] for p in points], '--', color='#555555', linewidth=0.8, zorder=1)
            polygons.append(shapes.outline(o))
            faces.append(colour[:3] + (0.2,))
            edges.append('#888888')
            widths.append(0.5)
        polygons.append(shapes.outline(o, x, y))
        faces.append(colour)
        edges.append('#d62728' if o.name in touched else '#333333')
        widths.append(2.5 if o.name in touched else 0.4)
    if polygons:
        axes.add_collection(PolyCollection(polygons, facecolors=faces, edgecolors=edges, linewidths=widths, zorder=2))
    # The goal and the start.
    if goal is not None:
        if success_radius:
            axes.add_patch(Circle(goal, success_radius, facecolor='#1f77b4', alpha=0.15, edgecolor='#1f77b4', zorder=3))
        axes.plot(*goal, marker='*', markersize=14, color='#1f77b4', zorder=6)
    rect = (footprint.x_min, footprint.x_max, footprint.y_min, footprint.y_max)

    def robot(pose, **style):
        axes.add_patch(Polygon(shapes.robot_corners(pose, rect), closed=True, **style))

    robot(start, fill=False, edgecolor='#555555', linestyle='--', linewidth=1.2, zorder=5)
    handles = [Line2D([], [], color='#555555', linestyle='--', label='start')]
    # The path.
    if len(rows) > 1:
        segments = [((a[1], a[2]), (b[1], b[2])) for a, b in zip(rows, rows[1:])]
        modes = [r[7] for r in rows[:-1]]
        by_mode = colour_by == 'mode' or (colour_by is None and any(m is not None for m in modes))
        if by_mode:
            colours = _mode_colours(modes)
            lines = LineCollection(segments, colors=[colours[m] for m in modes], linewidths=2.2, zorder=4)
            handles += [Line2D([], [], color=c, linewidth=2.2, label=m) for m, c in colours.items() if m is not None]
        else:
            lines = LineCollection(segments, cmap='viridis', linewidths=2.2, zorder=4)
            lines.set_array([abs(r[4]) for r in rows[:-1]])
            figure.colorbar(lines, ax=axes, shrink=0.7, label='speed (m/s)')
        axes.add_collection(lines)
    if rows:
        pose = rows[-1]
        robot(_pose(pose), facecolor='#333333', alpha=0.35, edgecolor='#000000', linewidth=1.2, zorder=5)
        handles.append(Line2D([], [], color='#000000', label='end'))
        closest = min(rows, key=lambda r: r[8] if len(r) > 8 and r[8] is not None else math.inf)
        if len(closest) > 8 and closest[8] is not None and math.isfinite(closest[8]):
            robot(_pose(closest), fill=False, edgecolor='#ff7f0e', linewidth=1.8, zorder=5)
            axes.annotate('least clearance %.3f m at %.1f s' % (closest[8], closest[0]), (closest[1], closest[2]),
                          xytext=(12, -18), textcoords='offset points', fontsize=8, color='#a04000', zorder=7)
            handles.append(Line2D([], [], color='#ff7f0e', label='least clearance'))
    for t, x, y, _yaw, names in contacts:
        axes.plot(x, y, marker='X', markersize=12, color='#d62728', markeredgecolor='white', zorder=8)
        axes.annotate('contact %.1f s%s' % (t, ': ' + ', '.join(names) if names else ''), (x, y), xytext=(10, 8),
                      textcoords='offset points', fontsize=8, color='#d62728', zorder=8)
    if contacts:
        handles.append(Line2D([], [], color='#d62728', marker='X', linestyle='', label='contact'))
    axes.legend(handles=handles, loc='best', fontsize=8, framealpha=0.85)
    axes.set_xlabel('x (m, world)')
    axes.set_ylabel('y (m, world)')
    axes.set_title(title(result, label), fontsize=10)
    axes.grid(True, alpha=0.25)
    figure.tight_layout()
    out = io.BytesIO()
    figure.savefig(out, format='png', dpi=DPI)
    pyplot.close(figure)
    return out.getvalue()


def _pose(row):
    from closed_loop.geometry import Pose2D
    return Pose2D(row[1], row[2], row[3])


def _mode_colours(modes):
    colours, spare = {None: '#aaaaaa'}, list(PALETTE)
    for mode in modes:
        if mode not in colours:
            colours[mode] = MODE_COLOURS.get(mode) or (spare.pop(0) if spare else '#333333')
    return colours


def _limits(rows, start, goal):
    """((x min, x max), (y min, y max)) round what matters: the path, the start and the goal, with a margin (a
    world's far walls may lie well outside)."""
    xs = [start.x] + [r[1] for r in rows] + ([goal[0]] if goal is not None else [])
    ys = [start.y] + [r[2] for r in rows] + ([goal[1]] if goal is not None else [])
    xs = [x for x in xs if math.isfinite(x)]
    ys = [y for y in ys if math.isfinite(y)]
    return (min(xs) - MARGIN_M, max(xs) + MARGIN_M), (min(ys) - MARGIN_M, max(ys) + MARGIN_M)
