"""Recording the loop with rosbag: what to record, where, with which limits, and whether it can be written.

The folder and name the user gives are handed to ``rosbag record`` as plain arguments (an argv list,
never a shell command line), so spaces, quotes and backticks in them are just characters of a path.
Before rosbag starts, :func:`bag_dir_problem` checks that the folder can be made and written and has
room; the node checks the room again while recording, since rosbag itself only logs when the disk is
nearly full and records nothing more. Free of ROS.
"""
import dataclasses
import os
import re
import shutil
import tempfile

from closed_loop.settings import SettingsError, param

#: The loop's topics, recorded by default (``~images`` adds the camera image, the bulk of a bag).
LOOP_TOPICS = ('/cmd_vel', '/scan', '/camera/camera_info', '/odom', '/tf', '/tf_static', '/obstacle_distance',
               '/red_detected', '/base_pose_ground_truth', '/contact', '/contact_count')
IMAGE_TOPICS = ('/camera/image_raw',)
MB = 1024 * 1024
#: A ROS graph resource name (global, relative or private), as rosbag takes topics.
TOPIC_NAME = re.compile(r'^[~/]?[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*$')


@dataclasses.dataclass
class RecordSettings:
    """record_bag's ``~parameters``."""
    bag_dir: str = param('~/.ros/closed_loop_bags', '', 'folder for the bags (created if missing; ~ is '
                         'the home folder)')
    bag_name: str = param('closed_loop', '', 'bag name prefix; rosbag adds _<date-time>.bag')
    images: bool = param(True, '', 'record /camera/image_raw too')
    compress: bool = param(False, '', 'lz4-compress chunks')
    split_size_mb: int = param(1024, 'MiB', 'start a new bag file at this size (rosbag --split --size)',
                               minimum=1, maximum=1024 * 1024)
    max_splits: int = param(4, '', 'keep at most this many bag files, deleting the oldest (rosbag '
                            '--max-splits); 0 keeps all', minimum=0)
    duration: float = param(0.0, 's', 'stop recording after this long (wall clock); 0 = no limit',
                            minimum=0.0)
    min_free_mb: int = param(1024, 'MiB', 'refuse to start, and fail while recording, when the folder\'s '
                             'disk has less free space than this (rosbag stops writing under 1 GiB)',
                             minimum=1)
    topics: str = param('', '', 'more topics to record, separated by spaces')

    def check_together(self):
        for topic in self.topics.split():
            if not TOPIC_NAME.match(topic):
                raise SettingsError('~topics: expected ROS topic names separated by spaces, got %r'
                                    % (topic,))
        name = self.bag_name
        if not name or '/' in name or name in ('.', '..') or '\0' in name:
            raise SettingsError('~bag_name: expected a file name (no "/"), got %r' % (name,))
        if not self.bag_dir or '\0' in self.bag_dir:
            raise SettingsError('~bag_dir: expected a folder path, got %r' % (self.bag_dir,))


@dataclasses.dataclass
class ScenarioRecordSettings:
    """scenario_recorder's ``~parameters``: one bag of a whole scenario, every topic from simulated t = 0."""
    bag: str = param('', '', 'the bag file to write (its folder is created; ~ is the home folder); it is '
                     'written as BAG.part and renamed when the recorder stops')
    min_free_mb: int = param(64, 'MiB', "refuse to start, and stop recording, when the bag folder's disk has "
                             'less free space than this', minimum=1)

    def check_together(self):
        if not self.bag.endswith('.bag') or '\0' in self.bag:
            raise SettingsError('~bag: expected a path to a .bag file, got %r' % (self.bag[:200],))


def bag_folder(settings):
    """The bag folder as an absolute path (``~`` expanded)."""
    return os.path.abspath(os.path.expanduser(settings.bag_dir))


def topics(settings):
    """The topics to record, in order, without repeats."""
    wanted = list(LOOP_TOPICS) + (list(IMAGE_TOPICS) if settings.images else []) + settings.topics.split()
    return list(dict.fromkeys(wanted))


def rosbag_argv(settings):
    """The ``rosbag record`` command as an argv list (no shell ever sees it)."""
    argv = ['rosbag', 'record', '--output-prefix=' + os.path.join(bag_folder(settings), settings.bag_name),
            '--split', '--size=%d' % settings.split_size_mb, '--max-splits=%d' % settings.max_splits,
            '--repeat-latched']
    if settings.compress:
        argv.append('--lz4')
    # (~duration is kept by the node, which stops rosbag: with --split, rosbag's --duration splits.)
    return argv + ['--'] + topics(settings)


def free_mb(folder):
    """Free space (MiB) on the disk that holds ``folder``."""
    return shutil.disk_usage(folder).free / MB


def room_problem(folder, min_free_mb):
    """Why there is not room to record in ``folder``, or None."""
    try:
        free = free_mb(folder)
    except OSError as error:
        return 'cannot read the free space of %s: %s' % (folder, error.strerror or error)
    if free < min_free_mb:
        return '%s has %.0f MiB free, under ~min_free_mb (%d MiB)' % (folder, free, min_free_mb)
    return None


def bag_dir_problem(settings):
    """Why bags cannot be recorded in the bag folder (it is created if missing), or None when they can."""
    return folder_problem(bag_folder(settings), settings.min_free_mb)


def folder_problem(folder, min_free_mb):
    """Why a bag cannot be written in ``folder`` (created if missing), or None when it can."""
    try:
        os.makedirs(folder, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=folder, prefix='.closed_loop-probe-'):
            pass
    except OSError as error:
        return 'cannot write bags in %s: %s' % (folder, error.strerror or error)
    return room_problem(folder, min_free_mb)
