"""BARN-method worlds (closed_loop.sim.barn), the footprint lattice that guarantees their way
(closed_loop.sim.lattice), their difficulty metrics, and the generators' table and command."""
import math
import os
from types import SimpleNamespace

import numpy
import pytest
import yaml

from closed_loop.batch.episode import EpisodeError, EpisodeSpec, load_episode_world
from closed_loop.sim.lattice import STEPS, FootprintLattice
from closed_loop.sim import barn, barn_metrics, generators
from closed_loop.sim.planar_rays import PlanarRays
from closed_loop.sim.profiles import load_profile
from closed_loop.sim.world import load_world

JACKAL = load_profile('jackal')
CELL = 0.05
# A 0.5 x 0.4 m robot (turning circle 0.64 m across): it fits a 0.45 m corridor only lengthwise.
ROBOT = SimpleNamespace(x_min=-0.25, x_max=0.25, y_min=-0.2, y_max=0.2)


def corridor_grid(half, bend):
    """Walls of occupied cells (obstacles 0.05 m across) round a corridor 2 ``half`` + 1 cells wide between their
    surfaces: along +x, then (``bend``) turning to +y."""
    grid = numpy.ones((120, 120), bool)
    grid[60 - half:60 + half + 1, 0:60 + half + 1] = False           # along +x, to column 60
    if bend:
        grid[60 - half:120, 60 - half:60 + half + 1] = False         # then along +y
    else:
        grid[60 - half:60 + half + 1, :] = False
    return grid


def lattice(grid, margin=0.0):
    return FootprintLattice(grid, CELL, ROBOT, margin, 0.5 * CELL)


def test_a_corridor_narrower_than_the_turning_circle_is_passed_straight_but_not_round_a_bend():
    straight = lattice(corridor_grid(4, bend=False))
    goal = numpy.zeros((120, 120), bool)
    goal[60, 110] = True
    assert straight.reachable((60, 10, 0), goal)
    assert not straight.free[2, 60, 30]                      # it cannot stand across the corridor
    bend = lattice(corridor_grid(4, bend=True))
    up = numpy.zeros((120, 120), bool)
    up[110, 60] = True
    assert not bend.reachable((60, 10, 0), up)               # no room to turn at the corner
    roomy = corridor_grid(4, bend=True)
    roomy[45:76, 45:76] = False                              # a room at the corner, wider than the circle
    assert lattice(roomy).reachable((60, 10, 0), up)


def test_a_turn_is_refused_where_only_its_sweep_meets_an_obstacle():
    grid = numpy.zeros((80, 80), bool)
    # A post on the 22.5-degree line through a corner of the rectangle: clear of it at 0 and at 45 degrees.
    corner = math.hypot(0.25, 0.2)
    angle = math.atan2(0.2, 0.25) + math.radians(22.5)
    i, j = 40 + int(round(corner * math.sin(angle) / CELL)), 40 + int(round(corner * math.cos(angle) / CELL))
    grid[i, j] = True
    here = lattice(grid)
    assert here.free[0, 40, 40] and here.free[1, 40, 40]
    assert not here.turn[0, 40, 40]


def test_the_shortest_way_goes_round_a_block_and_is_no_shorter_than_the_straight_line():
    grid = numpy.zeros((100, 200), bool)
    grid[30:70, 95:105] = True                                # a block on the line
    goal = numpy.zeros((100, 200), bool)
    goal[50, 190] = True
    length, path = lattice(grid).shortest((50, 10, 0), goal)
    assert path[0] == (50, 10, 0) and path[-1][:2] == (50, 190)
    assert 180 * CELL < length < 180 * CELL * 1.5
    ys = [i for i, _, _ in path]
    assert max(abs(i - 50) for i in ys) > 20                   # round the block
    open_length, _ = lattice(numpy.zeros((100, 200), bool)).shortest((50, 10, 0), goal)
    assert open_length == pytest.approx(180 * CELL)
    assert lattice(grid).shortest((50, 10, 0), numpy.zeros((100, 200), bool)) == (math.inf, [])


def relaxed_lengths(here, start):
    """Every state's shortest way from ``start`` by plain relaxation to convergence over all states (the
    reference): {(row, column, heading): m}."""
    rows, cols = here.shape
    cost = {start: 0.0}
    changed = True
    while changed:
        changed = False
        for (i, j, k), c in list(cost.items()):
            di, dj = STEPS[k]
            step = c + here.cell_m * math.hypot(di, dj)
            nexts = [(ni, nj, k, step) for ni, nj in ((i + di, j + dj), (i - di, j - dj))
                     if 0 <= ni < rows and 0 <= nj < cols and here.free[k, ni, nj]]
            nexts += [(i, j, (k + 1) % 8, c)] if here.turn[k, i, j] else []
            nexts += [(i, j, (k - 1) % 8, c)] if here.turn[(k - 1) % 8, i, j] else []
            for ni, nj, nk, then in nexts:
                if here.free[nk, ni, nj] and then < cost.get((ni, nj, nk), math.inf):
                    cost[(ni, nj, nk)] = then
                    changed = True
    return cost


def test_a_diagonal_corridor_the_robot_fits_only_cell_by_cell_on_its_diagonal_is_a_way():
    ii, jj = numpy.mgrid[0:60, 0:60]
    grid = numpy.abs(ii - jj) >= 7                             # walls along a 45-degree corridor
    here = lattice(grid)
    free = here.free.any(axis=0)
    assert free[20, 20] and free[21, 21] and not free[20, 21] and not free[21, 20]    # joined corner to corner
    goal = numpy.zeros(grid.shape, bool)
    goal[50, 50] = True
    assert here.reachable((10, 10, 1), goal)
    assert here.shortest((10, 10, 1), goal)[0] == pytest.approx(40 * CELL * math.sqrt(2))


@pytest.mark.parametrize('seed', [0, 2, 3, 6])       # 6: no way
def test_the_shortest_way_is_the_relaxed_one_to_the_bit_and_a_real_way_of_that_length(seed):
    """(And reachable says so exactly where the relaxation reaches a goal cell.)"""
    rng = numpy.random.default_rng(seed)
    grid = numpy.zeros((30, 50), bool)
    for _ in range(2 + seed % 4):                              # blocks between the start and the goal cells
        i, j = rng.integers(0, 26), rng.integers(14, 44)
        grid[i:i + rng.integers(2, 12), j:j + rng.integers(2, 6)] = True
    goal = numpy.zeros(grid.shape, bool)
    goal[rng.integers(5, 25, 3), rng.integers(44, 50, 3)] = True
    here = lattice(grid)
    start = (15, 7, seed % 8)
    length, path = here.shortest(start, goal)
    reference = relaxed_lengths(here, start)
    least = min([c for (i, j, _), c in reference.items() if goal[i, j]], default=math.inf)
    assert length == least                                     # to the bit
    assert here.reachable(start, goal) == math.isfinite(least)
    if math.isinf(least):
        assert path == []
        return
    assert path[0] == start and goal[path[-1][:2]]
    walked = 0.0
    for (i, j, k), (ni, nj, nk) in zip(path, path[1:]):
        assert here.free[nk, ni, nj]
        if (i, j) == (ni, nj):                                 # a turn in place, where its sweep is free
            assert here.turn[k, i, j] if nk == (k + 1) % 8 else (nk == (k - 1) % 8 and here.turn[nk, i, j])
        else:                                                  # a step along the heading, forward or back
            assert nk == k and (ni - i, nj - j) in (STEPS[k], (-STEPS[k][0], -STEPS[k][1]))
            walked += CELL * math.hypot(ni - i, nj - j)
    assert walked == pytest.approx(length, abs=1e-9)


def barn_settings(**values):
    return generators.settings_from(dict({'method': 'barn'}, **values), 'jackal')


def test_a_barn_world_is_the_same_for_the_same_seed_and_has_its_way():
    settings = barn_settings(seed=3, fill=0.45, smoothing=3)
    world = barn.generate(settings, JACKAL)
    assert world == barn.generate(settings, JACKAL)
    assert world != barn.generate(barn_settings(seed=4, fill=0.45, smoothing=3), JACKAL)
    posts = [o for o in world['obstacles'] if o['type'] == 'cylinder']
    assert 150 < len(posts) < 450 and all(o['radius'] == 0.075 for o in posts)
    field = barn.field_of_world(settings, world)
    length, poses = barn.way_length(settings, field, JACKAL)
    assert 9.5 < length < 14.0 and math.hypot(poses[-1][0] - 10.0, poses[-1][1]) <= 0.2
    load_world_ok = load_episode_world({'generator': {'method': 'barn', 'seed': 3, 'fill': 0.45, 'smoothing': 3}},
                                       JACKAL)
    assert len(load_world_ok.obstacles) == len(world['obstacles']) and load_world_ok.goal == (10.0, 0.0)


def test_a_way_with_more_room_than_the_guarantee_may_be_missing_and_one_wider_than_the_field_always_is():
    settings = barn_settings(seed=3, fill=0.45, smoothing=3)
    field = barn.field_of_world(settings, barn.generate(settings, JACKAL))
    assert barn.has_way(settings, field, JACKAL, settings.margin)            # the guarantee itself
    assert not barn.has_way(settings, field, JACKAL, 0.5 * settings.width_cells * settings.cell_m)
    # An empty field has a way for any room the side walls leave.
    empty = numpy.zeros_like(field)
    assert barn.has_way(settings, empty, JACKAL, 0.5)
    margins = [0.05, 0.1, 0.15, 0.2, 0.3]
    found = [barn.has_way(settings, field, JACKAL, m) for m in margins]
    assert found == sorted(found, reverse=True)                              # more room: never more ways


def test_walls_close_the_way_round_so_the_field_cannot_be_gone_round():
    # The way out of the start's and the goal's box is only through the field: every ray from the start and from
    # the goal meets a wall or a post within the box (as the LIDAR's planar caster sees them).
    world = load_episode_world({'generator': {'method': 'barn', 'seed': 3, 'fill': 0.2, 'smoothing': 2}}, JACKAL)
    walls = [o for o in world.obstacles if o.shape == 'box']
    assert len(walls) == 4
    caster = PlanarRays(world.obstacles)
    angles = numpy.linspace(-math.pi, math.pi, 720, endpoint=False)
    dirs = numpy.column_stack((numpy.cos(angles), numpy.sin(angles), numpy.zeros(720)))
    for x, y in ((0.0, 0.0), (10.0, 0.0)):
        ranges = caster.cast(None, (x, y, 0.3), dirs, 30.0)
        assert numpy.isfinite(ranges).all() and ranges.max() < math.hypot(12.5, 5.0), (x, y, ranges.max())


def test_the_field_drawn_again_when_it_leaves_no_way():
    settings = barn_settings(seed=0, fill=0.5, smoothing=3)
    field, attempt = barn.field_with_way(settings, JACKAL)
    assert attempt > 0
    layout = barn.Layout(settings)
    for earlier in range(attempt):
        blocked = barn.automaton(settings, numpy.random.default_rng([settings.seed, earlier]))
        grid, offset = layout.lattice(blocked, JACKAL)
        assert not grid.reachable(layout.start_state(offset), layout.goal_mask(offset))
    with pytest.raises(barn.BarnError, match='expected a lower fill'):
        barn.generate(barn_settings(seed=0, fill=0.9, smoothing=0), JACKAL)


@pytest.mark.parametrize('values, message', [
    ({'fill': 1.5}, 'fill: expected a number from 0 to 0.9'),
    ({'smoothing': -1}, 'smoothing: expected a whole number'),
    ({'goal_distance': 5.0}, 'goal_distance: expected at least 1 m beyond the field'),
    ({'fill_ratio': 0.3}, 'fill_ratio: not a setting of the barn generator'),
    ({'method': 'maze'}, 'method: expected one of corridor, barn'),
])
def test_bad_generator_settings_name_the_field(values, message):
    with pytest.raises(generators.GeneratorError, match=message):
        generators.settings_from(dict({'method': 'barn'}, **values), 'jackal')
    with pytest.raises(EpisodeError, match='world.generator.' + message.split(':')[0]):
        load_episode_world({'generator': dict({'method': 'barn'}, **values)}, JACKAL)


def test_the_metrics_rank_a_sparse_field_easier_than_a_dense_one():
    sparse_settings, dense_settings = barn_settings(seed=0, fill=0.4, smoothing=2), barn_settings(seed=2, fill=0.5,
                                                                                                     smoothing=4)
    sparse = barn_metrics.metrics(sparse_settings, barn.generate(sparse_settings, JACKAL), JACKAL)
    dense = barn_metrics.metrics(dense_settings, barn.generate(dense_settings, JACKAL), JACKAL)
    assert sparse.visibility_m > dense.visibility_m and sparse.characteristic_m > dense.characteristic_m
    assert sparse.closest_m > dense.closest_m
    assert 1.0 <= sparse.tortuosity and 1.0 <= dense.tortuosity
    assert sparse.way_m == pytest.approx(sparse.tortuosity * math.hypot(*sparse_path_span(sparse_settings)))


def sparse_path_span(settings):
    _, poses = barn.way_length(settings, barn.field_of_world(settings, barn.generate(settings, JACKAL)), JACKAL)
    return poses[-1][0] - poses[0][0], poses[-1][1] - poses[0][1]


def test_a_generated_world_is_made_once_and_handed_out_as_copies():
    settings = barn_settings(seed=5, fill=0.42, smoothing=3)
    first = generators.generate(settings, JACKAL)
    first['obstacles'].clear()
    assert generators.generate(settings, JACKAL)['obstacles']


def test_the_command_writes_barn_worlds_with_their_metrics(tmp_path):
    args = ['--method', 'barn', '--output', str(tmp_path), '--seed', '7', '--seeds', '2', '--fill', '0.42']
    assert generators.main(args) == 0
    files = sorted(os.listdir(tmp_path))
    assert files == ['barn_jackal_f042_m2_s7.yaml', 'barn_jackal_f042_m2_s8.yaml']
    with open(os.path.join(tmp_path, files[0])) as f:
        text = f.read()
    assert '--method barn' in text and '--seed 7' in text and '# BARN difficulty metrics' in text
    assert 'tortuosity' in text and 'characteristic dimension' in text
    world = load_world(os.path.join(tmp_path, files[0]), footprint=JACKAL.footprint)
    assert world.goal == (10.0, 0.0) and yaml.safe_load(text)['name'] == files[0][:-5]
    spec = EpisodeSpec(world=os.path.join(tmp_path, files[0]), robot='jackal', controller='avoid_obstacles')
    assert spec.world.endswith('.yaml')
