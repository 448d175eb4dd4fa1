#!/usr/bin/env python3
"""Time the simulator on the obstacle_course world: the core alone, then the node under ROS.

Run: ``python3 test/bench/bench_sim.py`` inside ``source env.sh`` (``make bench`` does that).
Options: ``--core-only`` skips the ROS part; ``--profile`` adds a cProfile of the core loop with the
camera off; ``--seconds S`` sets how long each node run is recorded.

1. Core (no ROS): a :class:`closed_loop.sim.simulation.Simulation` driven the way the node's loop drives it
   (a physics step and a contact check every step, the robot state at the odometry rate, scans and
   camera frames at their rates, a turn-in-place command at 10 Hz), without sleeping. Prints ms per
   physics step, scan and 320x240 camera frame (median, p95), what each part costs per simulated
   second, the CPU share the loop needs at real time and the real-time factor it can reach with the
   camera off.
2. Node (real ROS): a private master on port 11395, then ``sim.launch`` started three times with
   roslaunch: all sensors on at real_time_factor 1; camera off at real_time_factor 1 (the baseline for
   the LIDAR's jitter); camera off at real_time_factor 0. A subscriber in this process records the
   arrival wall times and stamps of /clock, /scan and the camera (so the camera is published to a
   subscriber, as in the closed loop); the node's CPU share comes from utime + stime in
   /proc/<pid>/stat and its peak memory from VmHWM in /proc/<pid>/status. Prints the real-time factor,
   the LIDAR's period jitter and the wall gaps of /clock (a stalled loop shows there), CPU and memory,
   each beside its target where there is one.

Targets: real time held with all sensors on using under 70 % of one core; at least 20x real time with
the camera off. Figures, not pass/fail: the exit status is non-zero only when a measurement could not
be made. Every process started here is stopped by its PID at the end, also on error or interruption.
"""
import argparse
import contextlib
import cProfile
import io
import os
import pstats
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
import xmlrpc.client

import numpy

ROOT = os.path.abspath(os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', '..'))
sys.path.insert(0, os.path.join(ROOT, 'src'))

WORLD = 'obstacle_course'
ROS_PORT = 11395
MASTER_URI = 'http://localhost:%d' % ROS_PORT
SIM_NODE = '/sim'  # the simulator's node name in launch/sim.launch

TARGET_CPU_PCT = 70.0          # % of one core, all sensors on at real time
TARGET_RTF_ALL_ON = 1.0        # real time held with all sensors on
TARGET_RTF_CAMERA_OFF = 20.0   # real_time_factor 0, camera off

# Core loop lengths in simulated s: 60 camera frames, and 200 scans over both loops.
CORE_CAMERA_ON_SIM_S = 6.0
CORE_CAMERA_OFF_SIM_S = 14.0
CORE_PROFILE_SIM_S = 5.0
CORE_WARMUP_STEPS = 200
# Turning in place keeps the robot clear of every obstacle however long the loop runs, while the scans
# and the camera's view still change from one sample to the next.
TURN_RATE_RPS = 0.8
COMMAND_PERIOD_S = 0.1  # simulated s between commands, as a 10 Hz controller sends them
PROFILE_LINES = 15

NODE_WINDOW_S = 15.0   # wall s recorded per node run
NODE_WARMUP_S = 2.0    # wall s after the first /clock before recording starts
START_TIMEOUT_S = 30.0  # for the master to answer and the node's first /clock and /scan
STOP_TIMEOUT_S = 20.0   # roslaunch's own escalation (SIGINT, then SIGTERM after 15 s) fits inside
POLL_S = 0.1
RTF_SUBWINDOW_S = 1.0  # the worst real-time factor is taken over windows this long
SUBSCRIBER_QUEUE = 1000
# What sim_node logs when it falls behind real time (counted in the launch output).
LAG_WARNING = 'cannot keep real_time_factor'

CLK_TCK = os.sysconf('SC_CLK_TCK')
KIB_PER_MIB = 1024.0


class BenchError(RuntimeError):
    """A measurement could not be made (a process did not start, a topic stayed silent, ...)."""


# -- formatting -----------------------------------------------------------------------------------------
def ms_stats(seconds):
    """(median, p95) in ms of a list of durations in s."""
    values = numpy.asarray(seconds) * 1e3
    return float(numpy.median(values)), float(numpy.percentile(values, 95))


def at_least(value, target, unit=''):
    return '(target >= %g%s, ratio %.2f)' % (target, unit, value / target)


def at_most(value, target, unit=''):
    return '(target < %g%s, ratio %.2f)' % (target, unit, value / target)


# -- 1. core --------------------------------------------------------------------------------------------
@contextlib.contextmanager
def quiet_stdio():
    """Silence file descriptors 1 and 2: pybullet prints its build time and a URDF warning from C."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = (os.dup(1), os.dup(2))
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        os.dup2(devnull, 2)
        yield
    finally:
        os.dup2(saved[0], 1)
        os.dup2(saved[1], 2)
        for fd in saved + (devnull,):
            os.close(fd)


PARTS = ('physics', 'contacts', 'state', 'scan', 'camera')


def run_core_loop(rig, sim_seconds, camera):
    """Drive ``rig`` (a closed_loop.sim.rig.Rig) for ``sim_seconds`` of simulated time as SimNode.run does,
    minus ROS and sleeping.

    Returns (wall s, CPU s of this process, {part: [s per call]}) for the parts in PARTS.
    """
    from closed_loop.sim import drive
    from closed_loop.sim.sensors.camera import Camera
    from closed_loop.sim.sensors.contacts import Contacts
    from closed_loop.sim.sensors.lidar import Lidar
    from closed_loop.sim.sensors.odometry import Odometry
    from closed_loop.sim.sensors.wheels import WheelEncoders
    sim, s = rig.sim, rig.all_settings
    samples = {part: [] for part in PARTS}
    scan_period, odom_period = 1.0 / s.scan_rate_hz, 1.0 / s.odom_rate_hz
    camera_period = 1.0 / s.camera_rate_hz
    half_step = 0.5 * sim.dt_s
    t = sim.time_s
    end = t + sim_seconds
    next_scan = next_odom = next_command = t
    next_camera = t + 0.5 * camera_period  # the node's half-period offset between scans and frames
    turn = drive.VelocityCommand(0.0, TURN_RATE_RPS)
    clock = time.perf_counter
    wall0, cpu0 = clock(), time.process_time()
    while t < end - half_step:
        if t >= next_command - half_step:
            next_command += COMMAND_PERIOD_S
            sim.command(turn)
        a = clock()
        t = sim.step()
        b = clock()
        rig.sample(Contacts)
        samples['physics'].append(b - a)
        samples['contacts'].append(clock() - b)
        if t >= next_odom - half_step:
            next_odom += odom_period
            a = clock()
            rig.sample(Odometry)
            rig.sample(WheelEncoders)
            samples['state'].append(clock() - a)
        if t >= next_scan - half_step:
            next_scan += scan_period
            a = clock()
            rig.sample(Lidar)
            samples['scan'].append(clock() - a)
        if camera and t >= next_camera - half_step:
            next_camera += camera_period
            a = clock()
            rig.sample(Camera)
            samples['camera'].append(clock() - a)
    return clock() - wall0, time.process_time() - cpu0, samples


def default_settings():
    """Every default of the simulator node's settings and its sensors', in one namespace."""
    import dataclasses
    import types
    from closed_loop.sim.scheduler import SchedulingSettings
    from closed_loop.sim.sensors import all_sensor_classes
    from closed_loop.sim.simulation import SimSettings
    merged = {}
    for cls in (SimSettings, SchedulingSettings) + tuple(c.settings_class for c in all_sensor_classes()
                                                         if c.settings_class is not None):
        merged.update({f.name: f.default for f in dataclasses.fields(cls)})
    return types.SimpleNamespace(**merged)


def make_simulation():
    with quiet_stdio():
        from closed_loop.sim import world
        from closed_loop.sim.rig import Rig
        loaded = world.load_world(world.resolve_world(WORLD, os.path.join(ROOT, 'worlds')))
        rig = Rig(loaded, {'world': WORLD}, os.path.join(ROOT, 'urdf', 'closed_loop.urdf'))
        for _ in range(CORE_WARMUP_STEPS):
            rig.sim.step()
    return rig


def core_benchmark(profile):
    """Part 1; returns {'cpu_pct_at_real_time', 'rtf_bound_camera_off'} for the summary."""
    sim = make_simulation()
    s = sim.all_settings
    try:
        on_wall, on_cpu, on = run_core_loop(sim, CORE_CAMERA_ON_SIM_S, camera=True)
        off_wall, off_cpu, off = run_core_loop(sim, CORE_CAMERA_OFF_SIM_S, camera=False)
        if profile:
            profiler = cProfile.Profile()
            profiler.enable()
            run_core_loop(sim, CORE_PROFILE_SIM_S, camera=False)
            profiler.disable()
    finally:
        with quiet_stdio():
            sim.close()
    if len(on['camera']) == 0 or len(on['scan']) + len(off['scan']) == 0:
        raise BenchError('the core loop rendered no frame or took no scan')

    print('1. Core: closed_loop.sim.simulation without ROS (%g + %g simulated s, as the node loops, no sleep)'
          % (CORE_CAMERA_ON_SIM_S, CORE_CAMERA_OFF_SIM_S))
    print('   %-34s %10s %10s %8s' % ('per call', 'median ms', 'p95 ms', 'samples'))
    rows = (('physics step (%g Hz)' % s.physics_rate_hz, on['physics'] + off['physics']),
            ('contact check (every step)', on['contacts'] + off['contacts']),
            ('robot state (%g Hz)' % s.odom_rate_hz, on['state'] + off['state']),
            ('LIDAR scan (%d rays)' % s.scan_samples, on['scan'] + off['scan']),
            ('camera frame (%dx%d)' % (s.camera_width, s.camera_height), on['camera']))
    for label, values in rows:
        median, p95 = ms_stats(values)
        print('   %-34s %10.3f %10.3f %8d' % (label, median, p95, len(values)))

    print('   %-34s %14s %15s' % ('cost per simulated second', 'camera on ms', 'camera off ms'))
    timed_on = timed_off = 0.0
    for part in PARTS:
        per_on = 1e3 * sum(on[part]) / CORE_CAMERA_ON_SIM_S
        per_off = 1e3 * sum(off[part]) / CORE_CAMERA_OFF_SIM_S
        timed_on += per_on
        timed_off += per_off
        print('   %-34s %14.1f %15.1f' % (part, per_on, per_off))
    print('   %-34s %14.1f %15.1f' % ('loop overhead', 1e3 * on_wall / CORE_CAMERA_ON_SIM_S - timed_on,
                                      1e3 * off_wall / CORE_CAMERA_OFF_SIM_S - timed_off))
    print('   %-34s %14.1f %15.1f' % ('total (wall)', 1e3 * on_wall / CORE_CAMERA_ON_SIM_S,
                                      1e3 * off_wall / CORE_CAMERA_OFF_SIM_S))
    print('   %-34s %14.1f %15.1f' % ('total (CPU of this process)', 1e3 * on_cpu / CORE_CAMERA_ON_SIM_S,
                                      1e3 * off_cpu / CORE_CAMERA_OFF_SIM_S))
    # CPU time, not wall time, for the bounds: the loop is single-threaded and CPU-bound, so the two
    # differ only by what other processes took from this one on the shared cores.
    cpu_pct = 100.0 * on_cpu / CORE_CAMERA_ON_SIM_S
    rtf_bound = CORE_CAMERA_OFF_SIM_S / off_cpu
    print('   all sensors on at real time: %.0f%% of one core for the core alone %s'
          % (cpu_pct, at_most(cpu_pct, TARGET_CPU_PCT, '%')))
    print('   camera off, as fast as possible: at most %.1fx real time on a free core before any ROS cost '
          '%s; %.1fx by wall time here' % (rtf_bound, at_least(rtf_bound, TARGET_RTF_CAMERA_OFF, 'x'),
                                          CORE_CAMERA_OFF_SIM_S / off_wall))
    if profile:
        out = io.StringIO()
        pstats.Stats(profiler, stream=out).sort_stats('tottime').print_stats(PROFILE_LINES)
        print('   cProfile of %g simulated s, camera off (by own time):' % CORE_PROFILE_SIM_S)
        for line in out.getvalue().splitlines():
            if line.strip() and not line.lstrip().startswith(('Ordered by', 'List reduced')):
                print('     ' + line.strip())
    print()
    return {'cpu_pct_at_real_time': cpu_pct, 'rtf_bound_camera_off': rtf_bound}


# -- 2. node: processes -----------------------------------------------------------------------------------
def proc_stat(pid):
    """The fields of /proc/<pid>/stat after the command name (index 0 is field 3, the state), or None."""
    try:
        with open('/proc/%d/stat' % pid) as f:
            text = f.read()
    except OSError:
        return None
    return text.rsplit(')', 1)[1].split()


def proc_cpu_s(pid):
    """utime + stime of a process (all its threads), in s."""
    fields = proc_stat(pid)
    if fields is None:
        raise BenchError('process %d is gone; cannot read its CPU time' % pid)
    return (int(fields[11]) + int(fields[12])) / float(CLK_TCK)


def proc_status_number(pid, key):
    """The first number of the ``key:`` line of /proc/<pid>/status (VmHWM in kB, a switch count, ...)."""
    try:
        with open('/proc/%d/status' % pid) as f:
            for line in f:
                if line.startswith(key + ':'):
                    return int(line.split()[1])
    except OSError:
        pass
    raise BenchError('cannot read %s of process %d' % (key, pid))


def preemptions(pid):
    """How often the process's main thread was switched out while it could still run (by other processes
    on the shared cores, or by its own threads)."""
    return proc_status_number(pid, 'nonvoluntary_ctxt_switches')


def child_processes(parent_pid):
    """(pid, start time) of each process whose parent is ``parent_pid``; the start time tells a reused
    PID apart."""
    children = []
    for entry in os.listdir('/proc'):
        if entry.isdigit():
            fields = proc_stat(int(entry))
            if fields is not None and int(fields[1]) == parent_pid:
                children.append((int(entry), fields[19]))
    return children


def start_group(cmd, log_path, env):
    """Start ``cmd`` in a new session (its own process group), output to ``log_path``."""
    with open(log_path, 'ab') as log:
        return subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                env=env, cwd=ROOT, start_new_session=True)


def stop_group(proc):
    """Stop a roscore or roslaunch started by :func:`start_group`, and every node it started.

    roslaunch stops its nodes on SIGINT; it starts each node in a session of its own, so the nodes
    are remembered by PID first and killed one by one if they outlive it.
    """
    if proc is None:
        return
    children = child_processes(proc.pid) if proc.poll() is None else []
    if proc.poll() is None:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGINT)
        try:
            proc.wait(STOP_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    for pid, started in children:
        fields = proc_stat(pid)
        if fields is not None and fields[19] == started and fields[0] != 'Z':
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def port_in_use(port):
    with contextlib.closing(socket.socket(socket.AF_INET, socket.SOCK_STREAM)) as sock:
        sock.settimeout(1.0)
        return sock.connect_ex(('127.0.0.1', port)) == 0


def lag_warnings(log_path):
    """How many times the node has logged that it fell behind real time, in its roslaunch output so far."""
    try:
        with open(log_path, errors='replace') as f:
            return f.read().count(LAG_WARNING)
    except OSError:
        return 0


def tail(path, chars=2000):
    try:
        with open(path, errors='replace') as f:
            return f.read()[-chars:]
    except OSError:
        return ''


# -- 2. node: recording -----------------------------------------------------------------------------------
class TopicLog:
    """Arrival wall times (time.monotonic, s) and stamps (s) of every message on one topic.

    Messages arrive as rospy.AnyMsg and only the stamp is unpacked (two uint32 at ``stamp_offset``):
    deserialising /clock at thousands per second or every image would load the cores being measured.
    """

    def __init__(self, rospy, topic, stamp_offset):
        self._lock = threading.Lock()
        self._offset = stamp_offset
        self.wall = []
        self.stamp = []
        self.sub = rospy.Subscriber(topic, rospy.AnyMsg, self._on, queue_size=SUBSCRIBER_QUEUE)

    def _on(self, msg):
        now = time.monotonic()
        secs, nsecs = struct.unpack_from('<II', msg._buff, self._offset)
        with self._lock:
            self.wall.append(now)
            self.stamp.append(secs + nsecs * 1e-9)

    def count(self):
        with self._lock:
            return len(self.wall)

    def between(self, start, end):
        """(arrival wall times, stamps) as arrays, for arrivals in [start, end]."""
        with self._lock:
            wall = numpy.array(self.wall)
            stamp = numpy.array(self.stamp)
        keep = (wall >= start) & (wall <= end)
        return wall[keep], stamp[keep]


CLOCK_STAMP_OFFSET = 0   # rosgraph_msgs/Clock: time clock
HEADER_STAMP_OFFSET = 4  # std_msgs/Header: uint32 seq, then time stamp


def real_time_factors(wall, stamp, subwindow_s):
    """(overall, worst over consecutive ``subwindow_s`` windows) of simulated s per wall s."""
    if len(wall) < 2 or wall[-1] <= wall[0]:
        raise BenchError('too few /clock messages to measure the real-time factor')
    overall = (stamp[-1] - stamp[0]) / (wall[-1] - wall[0])
    worst = overall
    edges = numpy.arange(wall[0], wall[-1] - subwindow_s + 1e-9, subwindow_s)
    for left in edges:
        inside = (wall >= left) & (wall <= left + subwindow_s)
        w, t = wall[inside], stamp[inside]
        if len(w) >= 2 and w[-1] > w[0]:
            worst = min(worst, (t[-1] - t[0]) / (w[-1] - w[0]))
    return overall, worst


def sim_node_pid(rospy, launch_pid):
    """The simulator's PID, asked from the node itself, and checked to be a child of our roslaunch."""
    import rosgraph
    master = rosgraph.Master(rospy.get_name(), master_uri=MASTER_URI)
    uri = master.lookupNode(SIM_NODE)
    code, message, pid = xmlrpc.client.ServerProxy(uri).getPid(rospy.get_name())
    if code != 1:
        raise BenchError('getPid of %s failed: %s' % (SIM_NODE, message))
    fields = proc_stat(pid)
    if fields is None or int(fields[1]) != launch_pid:
        raise BenchError('%s reports PID %d, which is not a child of our roslaunch (%d): another %s on '
                         'port %d?' % (SIM_NODE, pid, launch_pid, SIM_NODE, ROS_PORT))
    return pid


def node_run(rospy, label, launch_args, log_dir, env, window_s):
    """Start sim.launch with ``launch_args``, record ``window_s`` s after a warm-up, stop it; returns the
    figures as a dict."""
    cmd = ['roslaunch', '-p', str(ROS_PORT), 'closed_loop', 'sim.launch', 'world:=%s' % WORLD] + launch_args
    log_path = os.path.join(log_dir, 'roslaunch_%s.log' % label)
    print('   %s: %s' % (label, ' '.join(cmd)), flush=True)
    logs = {'clock': TopicLog(rospy, '/clock', CLOCK_STAMP_OFFSET),
            'scan': TopicLog(rospy, '/scan', HEADER_STAMP_OFFSET),
            'camera': TopicLog(rospy, '/camera/image_raw', HEADER_STAMP_OFFSET)}
    launch = None

    def wait(seconds, until=None):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            if launch.poll() is not None:
                raise BenchError('roslaunch exited (status %s); its output ends:\n%s'
                                 % (launch.returncode, tail(log_path)))
            if until is not None and until():
                return True
            time.sleep(POLL_S)
        return until is None

    try:
        launch = start_group(cmd, log_path, env)
        if not wait(START_TIMEOUT_S, lambda: logs['clock'].count() > 0 and logs['scan'].count() > 0):
            raise BenchError('no /clock and /scan from %s within %g s; roslaunch output ends:\n%s'
                             % (SIM_NODE, START_TIMEOUT_S, tail(log_path)))
        pid = sim_node_pid(rospy, launch.pid)
        wait(NODE_WARMUP_S)
        lags0 = lag_warnings(log_path)
        wall0, cpu0, own0, preempt0 = time.monotonic(), proc_cpu_s(pid), time.process_time(), preemptions(pid)
        wait(window_s)
        wall1, cpu1, own1, preempt1 = time.monotonic(), proc_cpu_s(pid), time.process_time(), preemptions(pid)
        lags = lag_warnings(log_path) - lags0
        peak_mib = proc_status_number(pid, 'VmHWM') / KIB_PER_MIB
        load = os.getloadavg()[0]
    finally:
        stop_group(launch)
        for log in logs.values():
            log.sub.unregister()

    clock_wall, clock_stamp = logs['clock'].between(wall0, wall1)
    rtf, worst_rtf = real_time_factors(clock_wall, clock_stamp, RTF_SUBWINDOW_S)
    scan_wall, scan_stamp = logs['scan'].between(wall0, wall1)
    camera_wall, _ = logs['camera'].between(wall0, wall1)
    if len(scan_wall) < 3:
        raise BenchError('only %d scans arrived in %g s' % (len(scan_wall), wall1 - wall0))
    sim_span = clock_stamp[-1] - clock_stamp[0]
    return {
        'wall_s': wall1 - wall0, 'rtf': rtf, 'worst_rtf': worst_rtf, 'lag_warnings': lags,
        'cpu_pct': 100.0 * (cpu1 - cpu0) / (wall1 - wall0), 'peak_mib': peak_mib,
        'recorder_cpu_pct': 100.0 * (own1 - own0) / (wall1 - wall0),
        'preemptions_per_s': (preempt1 - preempt0) / (wall1 - wall0), 'load': load,
        'clock_gap_max_s': float(numpy.max(numpy.diff(clock_wall))),
        'clock_gap_p99_s': float(numpy.percentile(numpy.diff(clock_wall), 99)),
        'scan_periods_s': numpy.diff(scan_wall), 'scan_stamp_periods_s': numpy.diff(scan_stamp),
        'scans': len(scan_wall), 'frames': len(camera_wall), 'sim_span_s': sim_span,
    }


#: (key, title, sim.launch arguments) of each node run, in order. The camera-off run at real time is
#: the baseline that tells the LIDAR jitter caused by rendering from the jitter of scheduling alone.
NODE_RUNS = (
    ('all_on', 'all sensors on, real_time_factor 1', ['real_time_factor:=1']),
    ('camera_off_rt', 'camera off, real_time_factor 1 (baseline for the LIDAR jitter)',
     ['real_time_factor:=1', 'camera:=false']),
    ('camera_off_fast', 'camera off, real_time_factor 0', ['real_time_factor:=0', 'camera:=false']),
)


def print_run(title, run, settings, real_time, core):
    """The figures of one node run; LIDAR period jitter only for runs paced at real time."""
    s = settings
    scan_period_ms = 1e3 / s.scan_rate_hz
    print('   %s, %.1f s:' % (title, run['wall_s']))
    if real_time:
        print('     real-time factor      %.3f, worst %g s window %.3f %s'
              % (run['rtf'], RTF_SUBWINDOW_S, run['worst_rtf'], at_least(run['rtf'], TARGET_RTF_ALL_ON)))
        print('     fell behind           %d lag warnings in the window (the node logs at most 1 per 10 s)'
              % run['lag_warnings'])
        print('     CPU                   %.0f%% of one core %s'
              % (run['cpu_pct'], at_most(run['cpu_pct'], TARGET_CPU_PCT, '%')))
        if run['frames']:
            print('       of which ROS layer  ~%.0f%% (the node minus the core loop at real time, %.0f%%)'
                  % (run['cpu_pct'] - core['cpu_pct_at_real_time'], core['cpu_pct_at_real_time']))
    else:
        print('     real-time factor      %.1fx %s'
              % (run['rtf'], at_least(run['rtf'], TARGET_RTF_CAMERA_OFF, 'x')))
        print('     CPU                   %.0f%% of one core (%.1fx per full core)'
              % (run['cpu_pct'], run['rtf'] * 100.0 / run['cpu_pct']))
        print('     per simulated s       %.1f ms wall, %.1f ms CPU of the node (the core loop alone: %.1f ms CPU)'
              % (1e3 / run['rtf'], 10.0 * run['cpu_pct'] / run['rtf'], 1e3 / core['rtf_bound_camera_off']))
    print('     peak memory (VmHWM)   %.0f MiB' % run['peak_mib'])
    print('     scheduling            main thread preempted %.0f times per s; load average %.1f; this recorder '
          '%.0f%% of one core' % (run['preemptions_per_s'], run['load'], run['recorder_cpu_pct']))
    periods_ms = 1e3 * run['scan_periods_s']
    if real_time:
        deviation_ms = numpy.abs(periods_ms - scan_period_ms)
        print('     /scan arrivals        %d; period mean %.1f ms, std %.2f ms, |period - %.0f ms| p95 %.1f ms, '
              'max %.1f ms' % (run['scans'], numpy.mean(periods_ms), numpy.std(periods_ms), scan_period_ms,
                               numpy.percentile(deviation_ms, 95), numpy.max(deviation_ms)))
    else:
        print('     /scan arrivals        %d (%.0f per wall s)' % (run['scans'], run['scans'] / run['wall_s']))
    stamp_dev_ms = numpy.abs(1e3 * run['scan_stamp_periods_s'] - scan_period_ms)
    lost = int(numpy.sum(1e3 * run['scan_stamp_periods_s'] > 1.5 * scan_period_ms))
    print('     /scan stamp periods   max |period - %.0f ms| %.2f ms; scans lost at the subscriber: %d'
          % (scan_period_ms, numpy.max(stamp_dev_ms), lost))
    if run['frames']:
        print('     camera frames         %d, %.1f per simulated s'
              % (run['frames'], run['frames'] / run['sim_span_s']))
    if real_time:
        print('     /clock wall gaps      p99 %.1f ms, max %.1f ms (one physics step is %.1f ms)'
              % (1e3 * run['clock_gap_p99_s'], 1e3 * run['clock_gap_max_s'], 1e3 / s.physics_rate_hz))


def node_benchmark(window_s, core):
    """Part 2; returns {run key: figures} for the summary."""
    import rospy
    if port_in_use(ROS_PORT):
        raise BenchError('port %d is in use (another master?); the benchmark needs it for a private master'
                         % ROS_PORT)
    log_dir = tempfile.mkdtemp(prefix='closed_loop_bench_')
    env = dict(os.environ, ROS_MASTER_URI=MASTER_URI, ROS_LOG_DIR=log_dir)
    os.environ.update(ROS_MASTER_URI=MASTER_URI, ROS_LOG_DIR=log_dir)
    print('2. Node: sim.launch on a private master (port %d), %g s recorded per run after %g s'
          % (ROS_PORT, window_s, NODE_WARMUP_S), flush=True)
    roscore = None
    runs = {}
    try:
        roscore = start_group(['roscore', '-p', str(ROS_PORT)], os.path.join(log_dir, 'roscore.log'), env)
        deadline = time.monotonic() + START_TIMEOUT_S
        while not port_in_use(ROS_PORT):
            if roscore.poll() is not None or time.monotonic() > deadline:
                raise BenchError('the master did not start; roscore output ends:\n%s'
                                 % tail(os.path.join(log_dir, 'roscore.log')))
            time.sleep(POLL_S)
        # Initialised before sim.launch sets /use_sim_time, so this node keeps wall time.
        rospy.init_node('sim_bench', anonymous=True, disable_signals=True)
        for key, _, launch_args in NODE_RUNS:
            runs[key] = node_run(rospy, key, launch_args, log_dir, env, window_s)
    finally:
        if rospy.core.is_initialized():
            rospy.signal_shutdown('benchmark done')
        stop_group(roscore)
        if len(runs) == len(NODE_RUNS):
            shutil.rmtree(log_dir, ignore_errors=True)
        else:
            print('   logs kept in %s' % log_dir, flush=True)
    settings = default_settings()
    print('   (LIDAR %d rays at %g Hz, camera %dx%d at %g Hz, physics %g Hz: the node\'s defaults)'
          % (settings.scan_samples, settings.scan_rate_hz, settings.camera_width, settings.camera_height,
             settings.camera_rate_hz, settings.physics_rate_hz))
    for key, title, launch_args in NODE_RUNS:
        print_run(title, runs[key], settings, 'real_time_factor:=1' in launch_args, core)
    print()
    return runs


def summary(core, node):
    print('Summary against the targets')
    if node:
        on, off = node['all_on'], node['camera_off_fast']
        print('  real time, all sensors on:     RTF %.3f %s' % (on['rtf'], at_least(on['rtf'], TARGET_RTF_ALL_ON)))
        print('  CPU, all sensors on:           %.0f%% of one core %s'
              % (on['cpu_pct'], at_most(on['cpu_pct'], TARGET_CPU_PCT, '%')))
        print('  real-time factor, camera off:  %.1fx %s'
              % (off['rtf'], at_least(off['rtf'], TARGET_RTF_CAMERA_OFF, 'x')))
        base = node['camera_off_rt']
        print('  LIDAR period jitter (std):     %.2f ms with the camera on, %.2f ms without'
              % (1e3 * numpy.std(on['scan_periods_s']), 1e3 * numpy.std(base['scan_periods_s'])))
    if core:
        print('  core alone (no ROS): CPU %.0f%% at real time %s; camera off %.1fx %s'
              % (core['cpu_pct_at_real_time'], at_most(core['cpu_pct_at_real_time'], TARGET_CPU_PCT, '%'),
                 core['rtf_bound_camera_off'], at_least(core['rtf_bound_camera_off'], TARGET_RTF_CAMERA_OFF, 'x')))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--core-only', action='store_true', help='skip the ROS part')
    parser.add_argument('--profile', action='store_true', help='cProfile the core loop with the camera off')
    parser.add_argument('--seconds', type=float, default=NODE_WINDOW_S,
                        help='wall s recorded per node run (default %(default)g)')
    args = parser.parse_args()
    if not args.seconds > 0:
        parser.error('--seconds: expected a number > 0, got %r' % args.seconds)
    # SIGTERM (as from a timeout) unwinds like Ctrl-C, so the finally blocks stop what was started.
    signal.signal(signal.SIGTERM, signal.default_int_handler)
    print('Simulator benchmark, world %s; %d cores, load average %.2f %.2f %.2f at start (the cores are '
          'shared: other load shows in the figures)' % ((WORLD, os.cpu_count()) + os.getloadavg()), flush=True)
    core = node = None
    try:
        core = core_benchmark(args.profile)
        if not args.core_only:
            node = node_benchmark(args.seconds, core)
    except BenchError as error:
        print('measurement failed: %s' % error, flush=True)
        return 1
    except KeyboardInterrupt:
        print('interrupted; every process this benchmark started has been stopped', flush=True)
        return 128 + signal.SIGINT
    summary(core, node)
    print('load average %.2f %.2f %.2f at the end' % os.getloadavg())
    return 0


if __name__ == '__main__':
    sys.exit(main())
