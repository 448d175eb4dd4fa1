"""The README's parameter tables say what the settings classes say: every ``~parameter`` of a node, none
more, with its default. The settings classes are the one source; this keeps the documentation honest."""
import dataclasses
import math
import os
import re

import pytest

from closed_loop import commands
from closed_loop.control import decisions, guard, markers, scan, state_machine, vision
from closed_loop.sim import scheduler, simulation
from closed_loop.sim.sensors import all_sensor_classes

README = os.path.join(os.path.dirname(__file__), '..', '..', 'README.md')
TABLE_HEADER = '| parameter | unit | default | meaning |'
# README heading (its text) -> the settings classes whose fields its parameter table lists. The simulator's
# table covers the node's own settings and those of every sensor class.
SECTIONS = {
    '### cmd_vel_marker': markers.MarkerSettings,
    '## The simulator: `sim_node`': (simulation.SimSettings, scheduler.SchedulingSettings)
    + tuple(cls.settings_class for cls in all_sensor_classes() if cls.settings_class is not None),
    '### velocity_publisher': commands.PublisherSettings,
    '### obstacle_detector': scan.DetectorSettings,
    '### stop_on_obstacle': decisions.StopSettings,
    '### state_machine_controller': state_machine.BackUpSettings,
    '## Safety inputs and `cmd_vel_guard`': guard.GuardSettings,
    '## vision_node: red-object detection': vision.VisionSettings,
}


def table_after(lines, heading):
    """{name: default text} from the first parameter table after ``heading``."""
    start = lines.index(heading)
    header = lines.index(TABLE_HEADER, start)
    rows = {}
    for line in lines[header + 2:]:
        if not line.startswith('|'):
            break
        cells = [c.strip() for c in line.strip('|').split('|')]
        rows[cells[0].strip('`').lstrip('~')] = cells[2]
    return rows


def readme_value(text):
    """A README default as a value: numbers (``pi/2 (1.5708)`` reads as its number), booleans, words."""
    text = text.strip('`')
    number = re.search(r'\(([-+0-9.e]+)\)$', text)
    if number:
        return float(number.group(1))
    if text.lower() in ('true', 'false'):
        return text.lower() == 'true'
    if text in ('-pi', 'pi'):
        return math.copysign(math.pi, -1 if text.startswith('-') else 1)
    try:
        return float(text)
    except ValueError:
        return text.strip("'\"")


@pytest.mark.parametrize('heading', sorted(SECTIONS))
def test_parameter_table_matches_the_settings_class(heading):
    lines = open(README).read().splitlines()
    assert heading in lines, 'README has no heading %r' % heading
    rows = table_after(lines, heading)
    classes = SECTIONS[heading] if isinstance(SECTIONS[heading], tuple) else (SECTIONS[heading],)
    fields = {f.name: f.default for cls in classes for f in dataclasses.fields(cls)}
    assert set(rows) == set(fields), 'README table under %r: missing %s, extra %s' % (
        heading, sorted(set(fields) - set(rows)), sorted(set(rows) - set(fields)))
    for name, default in fields.items():
        said = readme_value(rows[name])
        if isinstance(default, bool) or isinstance(default, str):
            assert said == default or (default == '' and said in ('', "''")), (name, rows[name], default)
        else:
            assert said == pytest.approx(default, rel=1e-3), (name, rows[name], default)
