"""Counter unwrapping modulo 2**bits in both directions across the wrap, and impossible jumps flagged."""
import pytest

from swim_hw_bridge.unwrap import JUMP_SLACK_COUNTS, CounterUnwrapper

BITS = 16
MODULUS = 1 << BITS


def unwrapper(max_counts_per_s=1e6):
    return CounterUnwrapper(BITS, [max_counts_per_s] * 2)


def test_forward_and_backward_across_the_wrap():
    counter = unwrapper()
    assert counter.update((MODULUS - 5, 3), 0.0) == 0
    assert counter.unwrapped == [0, 0]
    assert counter.update((4, MODULUS - 2), 0.008) == 0   # +9 forward through the wrap; -5 backward through 0
    assert counter.unwrapped == [9, -5]
    assert counter.update((MODULUS - 7, 10), 0.016) == 0  # back again: -11, +12
    assert counter.unwrapped == [-2, 7]


@pytest.mark.parametrize("direction", [1, -1])
def test_many_wraps_stay_exact(direction):
    counter = unwrapper()
    true_count, time_s = 12345, 0.0
    counter.update((true_count % MODULUS, 0), time_s)
    for _ in range(400):   # 400 steps of 3000 counts: about 18 wraps
        true_count += direction * 3000
        time_s += 0.008
        assert counter.update((true_count % MODULUS, 0), time_s) == 0
    assert counter.unwrapped[0] == direction * 400 * 3000


def test_a_step_beyond_the_speed_bound_is_flagged_on_its_channel_only():
    counter = CounterUnwrapper(BITS, [1000.0, 1000.0])   # at most 8 counts per 8 ms, plus the slack
    counter.update((0, 0), 0.0)
    assert counter.update((8 + JUMP_SLACK_COUNTS, 0), 0.008) == 0
    jumps = counter.update((10 + 500, 3), 0.016)
    assert jumps == 0b01
    assert counter.unwrapped == [510, 3]   # still accumulated: no better estimate exists
    jumps = counter.update((510, 3 - 300), 0.024)
    assert jumps == 0b10


def test_a_jump_through_the_wrap_is_flagged_too():
    counter = CounterUnwrapper(BITS, [1000.0])
    counter.update((MODULUS - 10,), 0.0)
    assert counter.update((200,), 0.008) == 0b1   # +210 counts in 8 ms


def test_standstill_noise_within_the_slack_is_not_a_jump():
    counter = CounterUnwrapper(BITS, [1000.0])
    counter.update((0,), 1.0)
    assert counter.update((JUMP_SLACK_COUNTS,), 1.0) == 0
    assert counter.update((2 * JUMP_SLACK_COUNTS + 1,), 1.0) == 0b1


def test_reset_counts_from_the_next_sample():
    counter = unwrapper()
    counter.update((100, 0), 0.0)
    counter.update((200, 0), 0.008)
    counter.reset()
    counter.update((5000, 0), 0.016)
    assert counter.unwrapped == [0, 0]
