"""Any row of a finished sweep, again: its spec re-run, to draw it (``rosrun closed_loop episode_plot OUTPUT
INDEX``) or to write it as a bag (``rosrun closed_loop episode_bag``, ``closed_loop.nodes.episode_bag``).

An in-process episode is deterministic: the re-run must give the row's outcome and final pose to the bit,
and :func:`differences` says where it did not. A graph episode runs on its own processes and clock: its
re-run is held to the same outcome and contacts, and a final position within :func:`graph_tolerance_m`.
Free of ROS.
"""
import argparse
import dataclasses
import json
import math
import os
import sys

from closed_loop import cli
from closed_loop.batch import sweep, sweep_report
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, run_episode
from closed_loop.batch.pictures import episode_picture
from closed_loop.sim.profiles import load_profile
from closed_loop.sim.sensors.lidar import LidarSettings

#: How close a graph episode's re-run must end to its row (m), at least: the agreement measured between graph
#: runs of this package's controllers, whose first decision is taken on the first scan.
GRAPH_TOLERANCE_M = 0.03
#: ... and the LIDAR periods of travel at the robot's top speed the re-run may end apart (see graph_tolerance_m).
GRAPH_TOLERANCE_PERIODS = 2


def graph_tolerance_m(result, scan_period_s):
    """How far (m) a graph episode's re-run may end from its row: a controller's timer phase against the
    simulator's scans is whatever its node's start-up made it, so a stop decided on a tick falls up to a scan
    period (the reading's age) plus a timer period (the tick) later in one run than in another; that is
    GRAPH_TOLERANCE_PERIODS LIDAR periods of travel at the top speed the re-run's track shows (a controller's
    rate taken as the LIDAR's), and never less than GRAPH_TOLERANCE_M."""
    top = max((abs(row[4]) for row in result.trajectory or ()), default=0.0)
    return max(GRAPH_TOLERANCE_M, GRAPH_TOLERANCE_PERIODS * scan_period_s * top)


class RerunError(ValueError):
    """No such sweep, row or spec; the message says which."""


def find_row(output, index):
    """(row, spec) of episode ``index`` in the sweep folder ``output``."""
    path = os.path.join(output, 'rows.csv')
    if not os.path.isfile(path):
        raise RerunError('%s: no rows.csv there (is it a sweep\'s --output folder?)' % output)
    for row in sweep.read_rows(path):
        if row.get('index') == str(index):
            try:
                return row, EpisodeSpec.from_dict(json.loads(row['spec']))
            except (ValueError, TypeError, EpisodeError) as error:
                raise RerunError('%s: row %s: its spec column is not an episode spec (%s)' % (path, index, error))
    raise RerunError('%s: no row with index %s' % (path, index))


def rerun(output, index, tap=None, logs=None, bag=None):
    """(row, spec, result, differences): episode ``index`` of the sweep in ``output`` run again, its trajectory
    kept, shown to ``tap`` (``closed_loop.batch.lockstep.Tap``) if given, or for a graph episode recorded into
    ``bag`` if given."""
    row, spec = find_row(output, index)
    if row['outcome'] == 'error' and not row.get('logs'):
        raise RerunError('row %s could not run in the sweep: %s' % (index, row.get('error') or row.get('why')))
    try:
        result = run_episode(dataclasses.replace(spec, keep_trajectory=True), {}, logs, tap, bag)
    except EpisodeError as error:
        raise RerunError('row %s: %s' % (index, error))
    tolerance = graph_tolerance_m(result, scan_period_s(spec)) if isinstance(spec.controller, dict) else None
    return row, spec, result, differences(row, result, tolerance)


def scan_period_s(spec):
    """The LIDAR period (s) of ``spec``'s robot: its profile's, or the spec's own sim override."""
    rate = dict(load_profile(spec.robot).node_params('sim'), **spec.sim).get('scan_rate_hz',
                                                                           LidarSettings().scan_rate_hz)
    return 1.0 / rate


def differences(row, result, graph_tolerance_m=None):
    """How ``result`` differs from the sweep's ``row``: [] when it reproduces it (the outcome and the contacts
    the same; the final pose to the bit, or for a graph episode, whose ``graph_tolerance_m`` is given, within
    that distance)."""
    found = []
    for name, value in (('outcome', result.outcome), ('contacts', str(result.contacts))):
        if row.get(name) != str(value):
            found.append('%s %s, the row says %s' % (name, value, row.get(name)))
    pose = result.final_pose
    try:
        was = tuple(float(row[k]) for k in ('final_x', 'final_y', 'final_yaw'))
    except (KeyError, ValueError):
        return found + ['the row has no final pose']
    if graph_tolerance_m is not None:
        off = math.hypot(pose[0] - was[0], pose[1] - was[1])
        if off > graph_tolerance_m:
            found.append('final position %.3f m from the row\'s (%.3f, %.3f), more than the %.3f m two runs of a '
                         'graph may differ by' % (off, was[0], was[1], graph_tolerance_m))
    elif tuple(pose) != was:
        found.append('final pose (%r, %r, %r), the row says (%r, %r, %r)' % (tuple(pose) + was))
    return found


def report_differences(index, found, stream=sys.stderr):
    """Say whether the re-run reproduced the row; True if it did."""
    if found:
        stream.write('episode %s: the re-run did NOT reproduce the row: %s\n' % (index, '; '.join(found)))
        return False
    stream.write('episode %s: the re-run reproduces the row\n' % index)
    return True


def row_parser(prog, description, out_help):
    """The command line of a tool that takes a row of a finished sweep: ``OUTPUT INDEX [--out FILE]``."""
    parser = cli.parser(prog, description)
    parser.add_argument('output', help="the sweep's folder (its --output, with rows.csv)")
    parser.add_argument('index', type=int, help="the row's index (rows.csv's index column)")
    parser.add_argument('--out', help=out_help)
    return parser


def plot_main(argv=None):
    """``episode_plot OUTPUT INDEX [--out FILE.png] [--colour-by mode|speed]``."""
    parser = row_parser('episode_plot', 'Draw a row of a finished sweep again, by re-running its spec: a top-down '
                        'picture of the episode (PNG).', 'the PNG to write (default: OUTPUT/pictures/episode-INDEX.png)')
    parser.add_argument('--colour-by', choices=('mode', 'speed'), help="the path's colour (default: the "
                        "controller's mode, where it has one)")
    args = parser.parse_args(argv)
    try:
        row, spec, result, found = rerun(args.output, args.index)
    except RerunError as error:
        print('episode_plot: %s' % error, file=sys.stderr)
        return 2
    out = args.out or sweep_report.picture_path(args.output, args.index)
    png = episode_picture(spec, result, label='episode %d' % args.index, colour_by=args.colour_by)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, 'wb') as f:
        f.write(png)
    print('episode %d: %s\npicture: %s' % (args.index, result.why, out))
    return 0 if report_differences(args.index, found) else 1
