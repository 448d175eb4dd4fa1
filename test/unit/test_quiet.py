"""pybullet's own output (its banner, its URDF importer's warnings) stays out of the terminal unless asked for,
and nothing else written meanwhile is lost."""
import os
import subprocess
import sys

from closed_loop.sim.quiet import native_output, without_noise

SRC = os.path.abspath(os.path.join(os.path.dirname(__file__), '..', '..', 'src'))
# What pybullet 3.2.7 printed loading the package's robot (two reports run together), and its banner.
IMPORTER = ('b3Warning[examples/Importers/ImportURDFDemo/BulletUrdfImporter.cpp,126]:\n'
            'No inertial data for link, using mass=1, localinertiadiagonal = 1,1,1, identity local inertial frame'
            'b3Warning[examples/Importers/ImportURDFDemo/BulletUrdfImporter.cpp,126]:\nbase_footprint')
BANNER = 'pybullet build time: Jan 29 2025 23:17:20\n'
EPISODE = ('import sys; sys.path.insert(0, %r)\n'
           'from closed_loop.batch.episode import EpisodeSpec, run_episode\n'
           'print("outcome", run_episode(EpisodeSpec(world="wall", time_limit_s=1.0)).outcome)\n' % SRC)


def test_pybullets_lines_are_taken_out_and_others_kept():
    assert without_noise(BANNER + IMPORTER) == ''
    assert without_noise('ours\n' + IMPORTER + '\nours too\n') == 'ours\nours too\n'
    assert without_noise('b3Printf: Selected demo: Physics Server\nkept\n') == 'kept\n'


def test_an_episode_prints_only_its_own_line_and_verbose_lets_pybullet_through():
    env = dict(os.environ)
    env.pop('CLOSED_LOOP_VERBOSE', None)
    quiet = subprocess.run([sys.executable, '-c', EPISODE], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                           universal_newlines=True, env=env, timeout=120)
    assert quiet.returncode == 0, quiet.stderr
    assert quiet.stdout == 'outcome timed_out\n' and quiet.stderr == ''
    loud = subprocess.run([sys.executable, '-c', EPISODE], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          universal_newlines=True, env=dict(env, CLOSED_LOOP_VERBOSE='1'), timeout=120)
    assert 'pybullet build time' in loud.stdout + loud.stderr and 'No inertial data' in loud.stdout + loud.stderr


def test_what_others_write_meanwhile_is_written_back(capfd):
    with native_output():
        os.write(1, b'b3Warning[x.cpp,1]:\nnoise\n')
        os.write(2, b'a line of ours\n')
    out, err = capfd.readouterr()
    assert 'noise' not in out + err and 'a line of ours' in err
