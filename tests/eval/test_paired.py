import numpy as np
import pytest

from surveil.eval.paired import paired_difference


def test_a_gain_in_every_run_is_told_from_noise():
    a = np.array([2, 4, 1, 0, 3, 2, 2, 4, 1, 0, 3, 2])
    r = paired_difference(a, a + 1)
    assert (r.total, r.n_higher, r.n_lower) == (12.0, 12, 0)
    assert r.low > 0
    assert r.p_sign < 0.001


def test_gains_and_losses_that_cancel_are_not():
    a = np.full(12, 3)
    b = a + np.tile([1, -1, 0], 4)
    r = paired_difference(a, b)
    assert r.total == 0.0
    assert r.low < 0 < r.high
    assert r.p_sign == 1.0


def test_one_lucky_run_does_not_make_a_gain():
    # most of the total from one cell: the interval reaches zero
    a = np.zeros(10)
    b = a.copy()
    b[3] = 4
    r = paired_difference(a, b)
    assert r.total == 4.0
    assert r.low == 0.0
    assert r.p_sign == 1.0


def test_same_input_and_seed_give_the_same_interval():
    rng = np.random.default_rng(5)
    a, b = rng.integers(0, 4, 30), rng.integers(0, 4, 30)
    assert paired_difference(a, b) == paired_difference(a, b)


def test_unpaired_figures_are_refused():
    with pytest.raises(ValueError, match="paired"):
        paired_difference(np.zeros(3), np.zeros(4))
