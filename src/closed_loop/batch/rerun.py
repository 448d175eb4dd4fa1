"""Any row of a finished sweep, again: its spec re-run, to draw it (``rosrun closed_loop episode_plot OUTPUT
INDEX``) or to write it as a bag (``rosrun closed_loop episode_bag``, ``closed_loop.nodes.episode_bag``).

An in-process episode is deterministic: the re-run must give the row's outcome and final pose to the bit,
and :func:`differences` says where it did not. A graph episode runs on its own processes and clock: its
re-run is held to the same outcome and a final pose within :data:`GRAPH_TOLERANCE_M`. Free of ROS.
"""
import argparse
import dataclasses
import json
import math
import os
import sys

from closed_loop.batch import sweep, sweep_report
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, run_episode
from closed_loop.batch.pictures import episode_picture

#: How close a graph episode's re-run must end to its row (m): the agreement measured between graph runs.
GRAPH_TOLERANCE_M = 0.03


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
    return row, spec, result, differences(row, result, graph=isinstance(spec.controller, dict))


def differences(row, result, graph=False):
    """How ``result`` differs from the sweep's ``row``: [] when it reproduces it (the outcome and the contacts
    the same; the final pose to the bit, or for a graph episode within GRAPH_TOLERANCE_M)."""
    found = []
    for name, value in (('outcome', result.outcome), ('contacts', str(result.contacts))):
        if row.get(name) != str(value):
            found.append('%s %s, the row says %s' % (name, value, row.get(name)))
    pose = result.final_pose
    try:
        was = tuple(float(row[k]) for k in ('final_x', 'final_y', 'final_yaw'))
    except (KeyError, ValueError):
        return found + ['the row has no final pose']
    if graph:
        off = math.hypot(pose[0] - was[0], pose[1] - was[1])
        if off > GRAPH_TOLERANCE_M:
            found.append('final position %.3f m from the row\'s (%.3f, %.3f)' % (off, was[0], was[1]))
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
    parser = argparse.ArgumentParser(prog=prog, description=description)
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
