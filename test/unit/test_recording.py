"""Recording: arguments for rosbag as a list (never a shell line), and folders that cannot take a bag."""
import os

import pytest

from closed_loop import recording
from closed_loop.settings import SettingsError, check


def settings(**values):
    return check(recording.RecordSettings(**values))


def test_argv_carries_folder_and_name_as_one_argument_each(tmp_path):
    folder = str(tmp_path / 'a b \'c\' "d" `touch x` $(reboot)')
    argv = recording.rosbag_argv(settings(bag_dir=folder, bag_name='my run'))
    assert argv[:2] == ['rosbag', 'record']
    assert '--output-prefix=' + os.path.join(folder, 'my run') in argv
    assert argv[argv.index('--') + 1:] == recording.topics(settings())


def test_default_limits_are_in_the_argv():
    argv = recording.rosbag_argv(settings(split_size_mb=10, max_splits=3, compress=True))
    assert '--split' in argv and '--size=10' in argv and '--max-splits=3' in argv and '--lz4' in argv


def test_topics_images_and_extras():
    assert '/camera/image_raw' not in recording.topics(settings(images=False))
    assert recording.topics(settings(topics='/a  b/c /cmd_vel'))[-2:] == ['/a', 'b/c']
    assert '/contact_count' in recording.topics(settings())


@pytest.mark.parametrize('values, field', [
    ({'topics': '--all'}, '~topics'),
    ({'topics': '/ok -O'}, '~topics'),
    ({'bag_name': 'a/b'}, '~bag_name'),
    ({'bag_name': ''}, '~bag_name'),
    ({'bag_dir': ''}, '~bag_dir'),
    ({'split_size_mb': 0}, '~split_size_mb'),
])
def test_bad_settings_are_refused_by_name(values, field):
    with pytest.raises(SettingsError, match=field):
        settings(**values)


def test_a_writable_folder_is_created(tmp_path):
    folder = tmp_path / 'new' / 'bags'
    assert recording.bag_dir_problem(settings(bag_dir=str(folder), min_free_mb=1)) is None
    assert folder.is_dir() and os.listdir(folder) == []


def test_a_folder_under_a_file_is_refused_by_name(tmp_path):
    (tmp_path / 'f').write_text('x')
    problem = recording.bag_dir_problem(settings(bag_dir=str(tmp_path / 'f' / 'bags')))
    assert problem is not None and str(tmp_path / 'f' / 'bags') in problem


def test_too_little_room_is_refused(tmp_path):
    problem = recording.bag_dir_problem(settings(bag_dir=str(tmp_path), min_free_mb=2 ** 40))
    assert problem is not None and 'MiB free' in problem and str(tmp_path) in problem


def test_home_is_expanded():
    assert recording.bag_folder(settings(bag_dir='~/x')) == os.path.join(os.path.expanduser('~'), 'x')
