"""compare's pairing and statistics (closed_loop.batch.compare.pair), on rows made by hand."""
import pytest

from closed_loop.batch.compare import pair


def row(index, outcome, clearance=0.3, time_s=5.0, contacts=0):
    return {'index': str(index), 'outcome': outcome, 'contacts': str(contacts), 'min_clearance_m': str(clearance),
            'time_s': str(time_s), 'spec': '{}'}


def test_pairs_are_counted_and_tested_as_mcnemar_has_it():
    a = [row(i, 'reached') for i in range(10)] + [row(10, 'timed_out'), row(11, 'collided', contacts=1)]
    b = ([row(i, 'reached', 0.2, 6.0) for i in range(7)] + [row(7, 'collided', contacts=1), row(8, 'timed_out'),
         row(9, 'reached', contacts=1)] + [row(10, 'reached'), row(11, 'timed_out')])
    c = pair(a, list(reversed(b)))                      # paired by index, not by order
    assert (c.regressions, c.fixes) == (3, 1)
    assert [p.kind for p in c.pairs][7:] == ['regression', 'regression', 'regression', 'fix', 'neither']
    # Exact McNemar: 3 of the 4 that differ one way, two-sided: P(X >= 3) + P(X <= 1) for X ~ Bin(4, 0.5).
    assert c.p_value == pytest.approx(10 / 16)
    share, low, high = c.regression_share
    assert share == 0.75 and 0.19 < low < 0.2 and high > 0.99        # the exact (Clopper-Pearson) interval
    mean, low, high = c.clearance_change                               # 0.3 -> 0.2 in every pair as meant both times
    assert mean == pytest.approx(-0.1) and low == pytest.approx(-0.1) and high == pytest.approx(-0.1)
    assert c.time_change[0] == pytest.approx(1.0)


def test_no_pair_that_differs_has_p_one_and_no_share():
    c = pair([row(0, 'reached')], [row(0, 'reached')])
    assert (c.regressions, c.fixes, c.p_value, c.regression_share, c.clearance_change) == (0, 0, 1.0, None, None)
