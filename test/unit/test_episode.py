"""Episodes: every controller in lockstep with the simulation, deterministic, judged on ground truth."""
import distributed
import pytest

from closed_loop.controllers import controller_classes
from closed_loop.batch.episode import EpisodeError, EpisodeSpec, run_episode


def test_every_controller_of_the_package_is_found():
    assert {'stop_on_obstacle', 'state_machine_controller', 'avoid_obstacles', 'fusion_controller'} \
        <= set(controller_classes())


def test_stop_on_obstacle_stops_at_the_wall_without_contact():
    result = run_episode(EpisodeSpec(world='wall', time_limit_s=20.0, keep_trajectory=True))
    assert result.outcome == 'stopped' and result.mode == 'STOP' and result.contacts == 0
    # The wall's face is at x = 3 m; the LIDAR (on the robot's axis) stops past stop_distance (0.5 m).
    assert 2.4 < result.final_pose[0] < 2.5 + 0.05
    assert 0.3 < result.peak_decel_mps2 and result.path_m == pytest.approx(result.final_pose[0], abs=0.05)
    assert [row[7] for row in result.trajectory][-1] == 'STOP'


def test_the_state_machine_backs_up_and_goes_again():
    result = run_episode(EpisodeSpec(world='wall', controller='state_machine_controller', time_limit_s=12.0,
                                     keep_trajectory=True))
    modes = [row[7] for row in result.trajectory]
    assert result.outcome == 'timed_out' and result.contacts == 0
    assert 'BACKING_UP' in modes and modes.index('BACKING_UP') < len(modes) - 1 - modes[::-1].index('EXPLORING')


def results_equal(a, b):
    return (a.outcome, a.mode, a.time_s, a.contacts, a.min_clearance_m, a.final_pose, a.path_m,
            a.peak_decel_mps2, a.trajectory) == (b.outcome, b.mode, b.time_s, b.contacts, b.min_clearance_m,
                                                 b.final_pose, b.path_m, b.peak_decel_mps2, b.trajectory)


NOISY = EpisodeSpec(world='obstacle_left', controller='avoid_obstacles', goal=(5.0, 0.0), scan_noise=0.01,
                    seed=7, time_limit_s=12.0, keep_trajectory=True)


def test_the_same_spec_gives_the_same_result_bit_for_bit():
    a, b = run_episode(NOISY), run_episode(NOISY)
    assert results_equal(a, b)
    c = run_episode(EpisodeSpec(**dict(NOISY.to_dict(), seed=8)))
    assert c.trajectory != a.trajectory          # the seed is the noise's: another seed, another run


def test_the_same_spec_in_two_worker_processes_gives_the_same_result():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host='127.0.0.1',
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        workers = sorted(client.scheduler_info()['workers'])
        assert len(workers) == 2
        futures = [client.submit(run_episode, NOISY, workers=[w], pure=False) for w in workers]
        one, two = client.gather(futures)
    assert results_equal(one, two) and results_equal(one, run_episode(NOISY))


@pytest.mark.parametrize('fields, message', [
    ({'controller': 'teleop'}, "controller: expected one of"),
    ({'robot': 'r2d2'}, 'robot: '),
    ({'world': 'atlantis'}, 'world'),
    ({'world': {'generator': {'fill_ratio': 2.0}}}, 'world.generator.fill_ratio'),
    ({'settings': {'stop_distance': 2.0}}, 'slow_distance'),
    ({'settings': {'stop_distanse': 0.4}}, 'settings.stop_distanse: not a parameter of stop_on_obstacle'),
    ({'sim': {'scan_samples': 0}}, 'sim: ~scan_samples'),
])
def test_an_unusable_spec_is_refused_naming_the_field(fields, message):
    with pytest.raises((EpisodeError, ValueError), match=message):
        run_episode(EpisodeSpec(**fields))


def test_a_spec_from_a_mapping_refuses_unknown_fields():
    assert EpisodeSpec.from_dict({'world': 'wall', 'goal': [1, 2]}).goal == (1, 2)
    with pytest.raises(EpisodeError, match=r'row 3\.speed: not an episode field'):
        EpisodeSpec.from_dict({'speed': 1.0}, where='row 3')
    assert EpisodeSpec.from_dict(EpisodeSpec(world={'generator': {'seed': 3}}).to_dict()).world == \
        {'generator': {'seed': 3}}


def test_an_episode_can_end_at_its_first_contact():
    # stop_distance 0.1 m: the robot's front is 0.15 m ahead of the LIDAR, so it drives into the wall.
    crash = dict(world='wall', settings={'stop_distance': 0.1, 'slow_distance': 0.6}, time_limit_s=20.0)
    whole = run_episode(EpisodeSpec(**crash))
    ended = run_episode(EpisodeSpec(end_on_contact=True, keep_trajectory=True, **crash))
    assert whole.outcome == ended.outcome == 'collided' and ended.contacts == 1
    assert whole.time_s == pytest.approx(20.0)
    assert 3.0 < ended.time_s < 15.0 and ended.trajectory[-1][0] <= ended.time_s
    assert 2.8 < ended.final_pose[0] < 3.0      # the wall's face is at x = 3 m; the robot's front is on it
    with pytest.raises(EpisodeError, match='end_on_contact: expected true or false'):
        run_episode(EpisodeSpec(end_on_contact='yes'))


def test_a_reused_pybullet_client_gives_the_result_of_a_fresh_one(monkeypatch):
    from closed_loop.sim import simulation
    first = run_episode(NOISY)             # whatever client this process had idle
    assert simulation._IDLE_CLIENTS            # closed, it left its client for the next
    run_episode(EpisodeSpec(world='posts', controller='state_machine_controller', time_limit_s=3.0))
    reused = run_episode(NOISY)
    monkeypatch.setattr(simulation, 'MAX_IDLE_CLIENTS', 0)
    import pybullet
    while simulation._IDLE_CLIENTS:
        pybullet.disconnect(physicsClientId=simulation._IDLE_CLIENTS.pop())
    fresh = run_episode(NOISY)
    assert not simulation._IDLE_CLIENTS
    assert results_equal(first, reused) and results_equal(fresh, reused)


@pytest.mark.parametrize('world, controller', [('posts', 'stop_on_obstacle'), ('obstacle_course', 'avoid_obstacles')])
def test_the_least_clearance_is_the_same_whether_or_not_the_track_is_kept(world, controller):
    """Without a track, the loop looks only for a clearance below the least so far: the least is unchanged."""
    kept = run_episode(EpisodeSpec(world=world, controller=controller, time_limit_s=15.0, keep_trajectory=True))
    lean = run_episode(EpisodeSpec(world=world, controller=controller, time_limit_s=15.0))
    assert kept.min_clearance_m == lean.min_clearance_m < 1.0
    assert kept.final_pose == lean.final_pose and kept.simulated_s == lean.simulated_s > kept.time_s - 1e-9
    assert min(row[8] for row in kept.trajectory) == kept.min_clearance_m
