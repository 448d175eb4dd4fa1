"""The lesson's second exercise, answered by a sweep: ``rosrun closed_loop tune_thresholds``.

For stop_on_obstacle at each cruise speed, it runs episodes over a range of stop distances (worlds, LIDAR
noise levels and seeds as given), each with the slow distance tied to it (below), on Dask as
``closed_loop.batch.sweep`` does, and recommends:

    the smallest stop distance at which every episode, at that cruise speed, ran without contact and kept a
    least clearance (ground truth, footprint to obstacle) of at least --margin;
    and a slow distance of that stop distance plus one second of travel at the cruise speed (the lesson's
    0.5 m and 1.0 m at 0.5 m/s keep exactly that gap), with which those episodes ran.

It prints that rule, the recommendation per speed and the evidence (per stop distance: episodes, contacts,
least clearance), and writes the rows, the summary, the plot, the pictures and the page as a sweep does,
the page with the rule and the recommendation at the top.
"""
import argparse
import sys

from closed_loop import cli
from closed_loop.batch import sweep, sweep_file

#: The slow zone begins this much travel (s at the cruise speed) before the stop zone.
SLOW_LEAD_S = 1.0
RULE = ('recommended stop_distance: the smallest tried at which every episode at that cruise speed ran with '
        'no contact and a least clearance of at least %.3f m; slow_distance: stop_distance + '
        '%.1f s x cruise_speed (the lesson\'s gap), as the episodes ran')


def build(speeds, stops, worlds, seeds, noises, time_limit_s, name='tune_thresholds'):
    """The sweep: every stop distance x cruise speed x world x noise x seed."""
    # An episode with contact has answered the question: it ends there.
    base = {'controller': 'stop_on_obstacle', 'time_limit_s': time_limit_s, 'end_on_contact': True}
    grid = {'settings.cruise_speed': speeds, 'settings.stop_distance': stops, 'world': worlds,
            'scan_noise': noises, 'seed': seeds}
    built = sweep_file.build(name, base, grid, {'x': 'settings.stop_distance', 'lines': 'settings.cruise_speed'})
    paired = []
    for assignment, spec in built.specs:
        speed = assignment['settings.cruise_speed']
        stop = assignment['settings.stop_distance']
        settings = dict(spec.settings, slow_distance=round(stop + SLOW_LEAD_S * speed, 10),
                        slow_speed=min(spec.settings.get('slow_speed', 0.2), speed))
        paired.append((assignment, spec.__class__(**dict(spec.to_dict(), settings=settings))))
    built.specs = paired
    return built


def recommend(rows, margin):
    """{cruise speed: (stop distance or None, {stop: (episodes, contacts, least clearance, errors)})}."""
    out = {}
    for row in rows:
        speed, stop = float(row['settings.cruise_speed']), float(row['settings.stop_distance'])
        evidence = out.setdefault(speed, {}).setdefault(stop, [0, 0, float('inf'), 0])
        evidence[0] += 1
        if row['outcome'] == 'error':
            evidence[3] += 1
            continue
        evidence[1] += int(row['contacts']) > 0
        evidence[2] = min(evidence[2], float(row['min_clearance_m']))
    result = {}
    for speed, by_stop in out.items():
        good = [stop for stop, (n, contacts, clearance, errors) in by_stop.items()
                if contacts == 0 and clearance >= margin and not errors]
        result[speed] = (min(good) if good else None, {k: tuple(v) for k, v in sorted(by_stop.items())})
    return result


def findings(rows, margin, evidence=False):
    """Lines: the rule, then the recommendation per cruise speed (with ``evidence``, per stop distance tried:
    episodes, contacts, least clearance)."""
    lines = ['rule: ' + RULE % (margin, SLOW_LEAD_S)]
    for speed, (stop, tried) in sorted(recommend(rows, margin).items()):
        if stop is None:
            lines.append('cruise %.2f m/s: no stop distance tried was safe in every episode; try larger ones' % speed)
        else:
            lines.append('cruise %.2f m/s: stop_distance %.2f m, slow_distance %.2f m'
                         % (speed, stop, stop + SLOW_LEAD_S * speed))
        if evidence:
            lines += ['    stop %.2f m: %d episodes, %d with contact, least clearance %.3f m%s%s'
                      % (s, n, contacts, clearance, ', %d failed to run' % errors if errors else '',
                         '  <- recommended' if s == stop else '')
                      for s, (n, contacts, clearance, errors) in tried.items()]
    return lines


def _floats(text):
    try:
        values = [float(v) for v in text.split(',') if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError('expected numbers separated by commas, got %r' % text)
    if not values:
        raise argparse.ArgumentTypeError('expected at least one number')
    return values


def main(argv=None):
    parser = cli.parser('tune_thresholds', __doc__.splitlines()[0])
    parser.add_argument('--speeds', type=_floats, default=[0.3, 0.5, 1.0], help='cruise speeds, m/s')
    parser.add_argument('--stops', type=_floats, default=[round(0.15 + 0.05 * i, 2) for i in range(10)],
                        help='stop distances to try, m')
    parser.add_argument('--worlds', default='wall,obstacle_left,red_box', help='worlds, by name or file')
    parser.add_argument('--seeds', type=int, default=3, help='seeds per combination (the LIDAR noise)')
    parser.add_argument('--noise', type=_floats, default=[0.0, 0.01], help='LIDAR noise levels (std), m')
    parser.add_argument('--margin', type=float, default=0.05, help='least clearance required, m')
    parser.add_argument('--time-limit', type=float, default=30.0, help='simulated seconds per episode')
    parser.add_argument('--output', help='directory for the rows, summary and plot (default: '
                        'sweeps/tune_thresholds)')
    sweep.add_cluster_arguments(parser)
    args = parser.parse_args(argv)
    status, _, rows = sweep.run_command('tune_thresholds', lambda: build(
        args.speeds, args.stops, [w for w in args.worlds.split(',') if w], list(range(args.seeds)), args.noise,
        args.time_limit), args.output, args, preface=lambda rows: findings(rows, args.margin))
    if status:
        return status
    print()
    print('\n'.join(findings(rows, args.margin, evidence=True)))
    return 0


if __name__ == '__main__':
    sys.exit(main())
