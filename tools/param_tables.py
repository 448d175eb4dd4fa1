#!/usr/bin/env python3
"""The docs' parameter tables, made from the settings classes (each parameter's one declaration).

    python3 tools/param_tables.py NODE       print NODE's table
    python3 tools/param_tables.py --write    rewrite every table in docs/ (after a settings class changed)
    python3 tools/param_tables.py --check    exit 1 if a table in docs/ differs (test_docs runs this check)

A table stands in docs/*.md after a line ``<!-- parameters: NODE -->`` and runs to the first line that does not
start with ``|``.
"""
import dataclasses
import glob
import math
import os
import re
import sys

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

from closed_loop import commands, recording  # noqa: E402
from closed_loop.control import guard, markers, scan, vision  # noqa: E402
from closed_loop.controllers import controller_classes  # noqa: E402
from closed_loop.batch import judge  # noqa: E402
from closed_loop.sim import scheduler, simulation  # noqa: E402
from closed_loop.sim.sensors import all_sensor_classes  # noqa: E402

MARKER = re.compile(r'^<!-- parameters: (\w+) -->$')


def node_settings():
    """{node name: its settings classes, in order}: every node of the package that reads ``~parameters``."""
    nodes = {
        'sim_node': (simulation.SimSettings, scheduler.SchedulingSettings)
        + tuple(c.settings_class for c in all_sensor_classes() if c.settings_class is not None),
        'velocity_publisher': (commands.PublisherSettings,),
        'obstacle_detector': (scan.DetectorSettings,),
        'cmd_vel_guard': (guard.GuardSettings,),
        'cmd_vel_marker': (markers.MarkerSettings,),
        'vision_node': (vision.VisionSettings,),
        'record_bag': (recording.RecordSettings,),
        'scenario_recorder': (recording.ScenarioRecordSettings,),
        'scenario_judge': (judge.JudgeSettings, judge.StartSettings),
        'start_when_ready': (judge.StartSettings,),
    }
    for name, cls in controller_classes().items():
        nodes[name] = (cls.settings_class,) + tuple(cls.extra_settings_classes)
    return nodes


def _value(value):
    if isinstance(value, bool):
        return 'true' if value else 'false'
    if isinstance(value, float):
        for name, number in (('pi', math.pi), ('pi/2', math.pi / 2), ('pi/4', math.pi / 4), ('-pi', -math.pi)):
            if value == number:
                return '%s (%.4f)' % (name, value)
        return '%g' % value
    if value == '':
        return "''"
    return str(value)


def _limits(meta):
    low, high = meta.get('minimum'), meta.get('maximum')
    parts = []
    if low is not None:
        parts.append('%s %s' % ('>' if meta.get('exclusive_minimum') else '>=', _value(low)))
    if high is not None:
        parts.append('<= %s' % _value(high))
    if meta.get('choices'):
        parts.append('one of %s' % ', '.join(_value(c) for c in meta['choices']))
    return ', '.join(parts)


def table(node):
    """NODE's parameter table, as Markdown lines."""
    lines = ['| parameter | unit | default | limits | live | meaning |', '|---|---|---|---|---|---|']
    seen = set()
    for cls in node_settings()[node]:
        for f in dataclasses.fields(cls):
            if f.name in seen:
                continue
            seen.add(f.name)
            meta = f.metadata
            lines.append('| `~%s` | %s | %s | %s | %s | %s |' % (
                f.name, meta.get('unit', ''), _value(f.default), _limits(meta), 'yes' if meta.get('live') else '',
                meta.get('doc', '').replace('|', '\\|')))
    return lines


def rewrite(text):
    """``text`` with every marked table made anew; raises KeyError for a marker naming no node."""
    out, lines, i = [], text.split('\n'), 0
    while i < len(lines):
        out.append(lines[i])
        match = MARKER.match(lines[i])
        i += 1
        if match:
            while i < len(lines) and lines[i].startswith('|'):
                i += 1
            out += table(match.group(1))
    return '\n'.join(out)


def docs():
    return sorted(glob.glob(os.path.join(ROOT, 'docs', '*.md')))


def main(argv=None):
    args = sys.argv[1:] if argv is None else argv
    if args in (['--write'], ['--check']):
        stale = []
        for path in docs():
            with open(path) as f:
                text = f.read()
            new = rewrite(text)
            if new != text:
                stale.append(os.path.relpath(path, ROOT))
                if args == ['--write']:
                    with open(path, 'w') as f:
                        f.write(new)
        if args == ['--check'] and stale:
            print('parameter tables differ from the settings classes in %s: run python3 tools/param_tables.py '
                  '--write' % ', '.join(stale))
            return 1
        return 0
    if len(args) == 1 and args[0] in node_settings():
        print('\n'.join(table(args[0])))
        return 0
    print(__doc__.strip() + '\n\nnodes: ' + ', '.join(sorted(node_settings())), file=sys.stderr)
    return 2


if __name__ == '__main__':
    sys.exit(main())
