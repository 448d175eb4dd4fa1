"""Every command-line program's --help gives each option's default (closed_loop.cli), a sweep is run by the
name of one the package ships, and Ctrl-C is known as Ctrl-C."""
import argparse
import importlib
import os

import pytest

from closed_loop import cli
from closed_loop.batch import sweep, sweep_file

#: (module, its main function, arguments): episode_bag is a node (rosbag, rospy), imported only where ROS is.
PROGRAMS = [('closed_loop.batch.sweep', 'main', ['x.yaml']), ('closed_loop.batch.tune_thresholds', 'main', []),
            ('closed_loop.batch.rerun', 'plot_main', ['out', '0']), ('closed_loop.nodes.episode_bag', 'main', ['out', '0']),
            ('closed_loop.sim.generators', 'main', ['--method', 'corridor']),
            ('closed_loop.sim.generators', 'main', ['--method', 'barn'])]


@pytest.mark.parametrize('module, function, argv', PROGRAMS)
def test_help_gives_every_options_default(monkeypatch, module, function, argv):
    if module.startswith('closed_loop.nodes.'):
        pytest.importorskip('rosbag', reason='a node: ROS 1 is not on this interpreter (make compat)')
    main = getattr(importlib.import_module(module), function)
    parsers = []

    def caught(parser, *_args, **_kwargs):
        parsers.append(parser)
        raise SystemExit(0)
    monkeypatch.setattr(argparse.ArgumentParser, 'parse_args', caught)
    with pytest.raises(SystemExit):
        main(argv)
    (parser,) = parsers
    formatter = parser._get_formatter()
    options = [a for a in parser._actions if a.option_strings and a.help != argparse.SUPPRESS
               and not isinstance(a, argparse._HelpAction) and not a.required]
    assert options
    for action in options:
        text = formatter._expand_help(action) if action.help else ''
        assert 'default' in text, '%s %s: %r' % (parser.prog, action.option_strings[0], text)
    help_text = parser.format_help()
    assert '%(' not in help_text


def test_a_shipped_sweep_is_run_by_its_name_and_an_unknown_name_lists_them():
    names = sweep_file.shipped()
    assert {'stop_thresholds', 'avoid_worlds'} <= set(names)
    for name in names:
        assert sweep_file.resolve(name) == os.path.join(sweep_file.paths.data_path('config', 'sweeps'),
                                                         name + '.yaml')
        built = sweep_file.load(name)
        assert built.name == name and 1 <= len(built.specs) <= 60      # tens of episodes: under a minute on 2 cores
    with pytest.raises(sweep_file.SweepError) as error:
        sweep_file.resolve('no_such_sweep')
    assert "'no_such_sweep': no such sweep file" in str(error.value) and 'stop_thresholds' in str(error.value)


def _raised_while_interrupted():
    try:
        try:
            raise KeyboardInterrupt
        finally:
            raise RuntimeError('cannot release un-acquired lock')
    except RuntimeError as error:
        return error


def test_ctrl_c_is_an_interrupt_also_when_a_library_raised_while_it_unwound():
    import threading
    assert cli.interrupted(KeyboardInterrupt())
    assert cli.interrupted(_raised_while_interrupted())
    # The error CPython's threading gives when a KeyboardInterrupt lands inside "with condition:" -- as a real one.
    lock = threading.Lock()
    try:
        try:
            with lock:
                raise KeyboardInterrupt
        finally:
            lock.release()
    except RuntimeError as error:
        assert cli.interrupted(error)
    else:
        raise AssertionError('releasing an unlocked lock did not raise')


def test_other_errors_are_not_interrupts():
    assert not cli.interrupted(RuntimeError('cannot release un-acquired lock'))
    try:
        try:
            raise ValueError('bad')
        finally:
            raise RuntimeError('then this')
    except RuntimeError as error:
        assert not cli.interrupted(error)
    looped = RuntimeError('a')
    looped.__context__ = RuntimeError('b')
    looped.__context__.__context__ = looped
    assert not cli.interrupted(looped)
