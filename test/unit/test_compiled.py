"""The compiled loops where nothing can be cached: a read-only copy of the package run by a user with no
writable home (an install space in a system folder) compiles them in the process and gets the same results."""
import os
import shutil
import subprocess
import sys
import tempfile

import machine

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
CHECK = """
import numpy
from closed_loop.control.navigation import wave_kernel
from closed_loop.sim.planar_rays import PlanarRays
from closed_loop.sim.world import parse_world
world = parse_world({'name': 'one', 'robot': {'start': {'x': 0.0, 'y': 0.0, 'yaw': 0.0}},
                     'obstacles': [{'name': 'c', 'type': 'cylinder', 'position': [2.0, 0.0], 'radius': 0.5,
                                    'height': 1.0}]})
ranges = PlanarRays(world.obstacles).cast(None, (0.0, 0.0, 0.2), numpy.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), 10.0)
k, steps = wave_kernel.wave(numpy.ones((3, 5), bool), (1, 0), (1, 4), 254)
print(ranges.tolist(), k, wave_kernel.wave.stats.cache_path is None or not os.access(wave_kernel.wave.stats.cache_path, os.W_OK))
"""


@machine.needs_capabilities_dropped()
def test_where_no_cache_can_be_written_the_loops_compile_in_the_process():
    folder = tempfile.mkdtemp(prefix='closed_loop_read_only_')
    try:
        os.chmod(folder, 0o755)
        shutil.copytree(os.path.join(SRC, 'closed_loop'), os.path.join(folder, 'closed_loop'),
                        ignore=shutil.ignore_patterns('__pycache__'))
        for here, dirs, files in os.walk(folder):
            for name in dirs + files:
                os.chmod(os.path.join(here, name), 0o555 if name in dirs else 0o444)
        os.chmod(folder, 0o555)
        # The home is the read-only folder too: without capabilities even root cannot make ~/.cache there (a home
        # that does not exist would not do: root owns / and could make it).
        env = dict(os.environ, HOME=folder, PYTHONPATH=folder, PYTHONDONTWRITEBYTECODE='1')
        for name in ('NUMBA_CACHE_DIR', 'XDG_CACHE_HOME'):
            env.pop(name, None)
        # The tests' own interpreter and packages, wherever they live and whoever may read them: only the
        # permission bits stop a write.
        check = machine.as_unprivileged([sys.executable, '-c', 'import os\n' + CHECK])
        done = subprocess.run(check, env=env, cwd='/', stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              universal_newlines=True, timeout=120)
        assert done.returncode == 0, done.stdout[-2000:]
        assert done.stdout.strip().splitlines()[-1] == '[1.5, inf] 4 True'
        assert not any('__pycache__' in dirs for _, dirs, _ in os.walk(folder))
    finally:
        for here, dirs, files in os.walk(folder):
            os.chmod(here, 0o755)
        shutil.rmtree(folder)
