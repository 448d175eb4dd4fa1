"""One source per safety input: a second publisher, or another frame, is refused and named."""
import pytest

from closed_loop.sources import SourceCheck


def test_one_publisher_in_the_right_frame_is_accepted():
    check = SourceCheck('/scan', 'base_scan')
    for t in range(20):
        assert check.observe('/sim', 'base_scan', 0.1 * t) is None


def test_a_second_publisher_is_refused_naming_both_until_it_is_gone():
    check = SourceCheck('/scan', 'base_scan', presence_s=1.0)
    assert check.observe('/sim', 'base_scan', 0.0) is None
    refused = check.observe('/spoofer', 'base_scan', 0.05)
    assert refused is not None and '/sim' in refused and '/spoofer' in refused and '/scan' in refused
    # The real source's own messages are refused too while the other is present.
    assert check.observe('/sim', 'base_scan', 0.1) is not None
    assert check.conflict(0.5) == ['/sim', '/spoofer']
    # The spoofer is silent for more than presence_s: trusted again.
    assert check.observe('/sim', 'base_scan', 1.2) is None
    assert check.conflict(1.2) is None


def test_a_connected_but_silent_second_publisher_counts():
    check = SourceCheck('/scan', None)
    assert check.observe('/sim', 'x', 0.0, connected=['/sim']) is None
    refused = check.observe('/sim', 'x', 0.1, connected=['/sim', '/other'])
    assert refused is not None and '/other' in refused


def test_a_scan_in_another_frame_is_refused():
    refused = SourceCheck('/scan', 'base_scan').observe('/sim', 'map', 0.0)
    assert refused is not None and "'map'" in refused and "'base_scan'" in refused and '/sim' in refused


def test_an_unknown_publisher_is_named_so():
    check = SourceCheck('/cmd_vel')
    check.observe(None, None, 0.0)
    assert '(unknown publisher)' in check.observe('/a', None, 0.1)


def test_a_clock_that_goes_back_forgets_the_future():
    check = SourceCheck('/scan')
    check.observe('/old', None, 10.0)
    assert check.observe('/sim', None, 1.0) is None


@pytest.mark.parametrize('bad', [0, -1, float('nan'), float('inf'), 'x'])
def test_bad_presence_is_refused(bad):
    with pytest.raises(ValueError):
        SourceCheck('/scan', presence_s=bad)
