"""The search's samplers (closed_loop.batch.search.sampler_of), each asked as the search asks it (a batch of
trials at a time, over the space's distributions), on a known function: every one runs with what provisioning
installs (CMA-ES needs the cmaes package), and the default one, TPE, comes closer to its low corner than chance.
(CMA-ES does not, in 40 trials: it starts from the middle of the space and a corner is its worst case.)"""
import pytest

from closed_loop.batch import search

SPACE = {'a': ('float', 0.0, 1.0), 'b': ('float', -1.0, 1.0), 'n': ('int', 0, 9)}


def low_corner(params):
    """Least (0) at a = 1, b = -1, n = 9."""
    return (1.0 - params['a']) ** 2 + (params['b'] + 1.0) ** 2 + (9 - params['n']) / 9.0


def best_of(sampler, seed, budget=40, batch=4):
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    plan = search.Search.__new__(search.Search)
    plan.sampler, plan.seed, plan.budget, plan.space = sampler, seed, budget, SPACE
    dists = search.distributions(plan)
    study = optuna.create_study(direction='minimize', sampler=search.sampler_of(plan))
    while len(study.trials) < budget:
        trials = [study.ask(dists) for _ in range(batch)]
        for trial in trials:
            study.tell(trial, low_corner(trial.params))
    return study.best_value


@pytest.mark.parametrize('sampler', search.SAMPLERS)
def test_every_sampler_runs_over_every_kind_of_parameter(sampler):
    assert 0.0 <= best_of(sampler, seed=0, budget=12) < 3.0


def test_tpe_comes_closer_than_chance():
    chance = sorted(best_of('random', seed) for seed in range(4))
    steered = sorted(best_of('tpe', seed) for seed in range(4))
    assert sum(steered) < 0.5 * sum(chance), (steered, chance)
