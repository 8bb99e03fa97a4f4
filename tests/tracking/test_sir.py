"""Pure SIR maths: resampling, weights, N_eff, likelihood (eq. 17), prediction, modes."""

from __future__ import annotations

import numpy as np
import pytest

from surveil.tracking import sir


def test_systematic_resample_splits_two_equal_weights_exactly(rng):
    w = np.zeros(20)
    w[[3, 7]] = 0.5
    counts = np.bincount(sir.systematic_resample(w, rng), minlength=20)
    assert counts[3] == counts[7] == 10 and counts.sum() == 20


def test_systematic_resample_all_weight_on_one_particle(rng):
    w = np.zeros(50)
    w[17] = 1.0
    assert np.all(sir.systematic_resample(w, rng) == 17)


def test_systematic_resample_counts_are_floor_or_ceil(rng):
    w = rng.random(37)
    w /= w.sum()
    counts = np.bincount(sir.systematic_resample(w, rng), minlength=37)
    assert np.all(counts >= np.floor(37 * w) - 1e-9) and np.all(counts <= np.ceil(37 * w) + 1e-9)


def test_systematic_resample_other_output_size(rng):
    idx = sir.systematic_resample(np.array([0.25, 0.75]), rng, 8)
    assert idx.dtype == np.intp and np.bincount(idx).tolist() == [2, 6]


def test_systematic_resample_rejects_bad_weights(rng):
    with pytest.raises(ValueError, match="weights"):
        sir.systematic_resample(np.array([-0.5, 1.5]), rng)


def test_block_resample_keeps_particles_in_their_block(rng):
    w = np.array([0.0, 1.0, 0.0, 0.5, 0.5, 0.0, 0.0, 0.0, 1.0])
    starts = np.array([0, 3, 6])
    idx = sir.block_systematic_resample(w, starts, rng)
    assert idx.tolist()[:3] == [1, 1, 1]
    assert sorted(idx.tolist()[3:6]) in ([3, 3, 4], [3, 4, 4])
    assert idx.tolist()[6:] == [8, 8, 8]


def test_block_resample_matches_per_block_counts(rng):
    n, t = 40, 5
    w = rng.random(n * t)
    starts = np.arange(t) * n
    owner = sir.block_owner(starts, n * t)
    w /= np.bincount(owner, weights=w)[owner]
    idx = sir.block_systematic_resample(w, starts, rng)
    assert np.all(owner[idx] == owner)
    counts = np.bincount(idx, minlength=n * t)
    assert np.all(np.abs(counts - n * w) < 1.0 + 1e-9)


def test_block_normalise_reports_degenerate_block():
    log_w = np.array([np.log(3.0), np.log(1.0), -np.inf, -np.inf, -np.inf])
    out, explained = sir.block_normalise(log_w, np.array([0, 2]))
    assert np.allclose(np.exp(out), [0.75, 0.25, 1 / 3, 1 / 3, 1 / 3])
    assert explained.tolist() == [True, False]


def test_starts_must_describe_nonempty_blocks():
    with pytest.raises(ValueError, match="starts"):
        sir.block_normalise(np.zeros(4), np.array([0, 2, 2]))


def test_effective_sample_size_uniform_and_degenerate():
    assert sir.effective_sample_size(np.full(16, 1 / 16)) == pytest.approx(16.0)
    assert sir.effective_sample_size(np.eye(1, 16)[0]) == 1.0
    # eq. 9 on two equal weights among many zeros
    w = np.zeros(10)
    w[[1, 2]] = 0.5
    assert sir.effective_sample_size(w) == pytest.approx(2.0)
    log_w = np.log(np.concatenate([np.full(4, 0.25), w]) + 1e-300)
    assert sir.block_effective_sample_size(log_w, np.array([0, 4])) == pytest.approx([4.0, 2.0])


def test_likelihood_matches_a_direct_sum(rng):
    x = rng.normal(size=(30, 3))
    z = rng.normal(size=(7, 3))
    p = rng.random(7)
    sigma = 0.7
    log_lik, support = sir.candidate_log_likelihood(x, z, p, sigma, clutter=0.01)
    ref = np.array(
        [
            sum(
                np.exp(-np.sum((xi - zc) ** 2) / (2 * sigma**2)) * pc
                for zc, pc in zip(z, p, strict=True)
            )
            for xi in x
        ]
    )
    assert np.allclose(support, ref)
    assert np.allclose(log_lik, np.log(ref + 0.01))
    assert log_lik.shape == (30,) and log_lik.dtype == np.float64


def test_likelihood_without_candidates_is_flat():
    log_lik, support = sir.candidate_log_likelihood(
        np.zeros((5, 3)), np.zeros((0, 3)), np.zeros(0), 0.03, clutter=1e-3
    )
    assert np.all(support == 0) and np.allclose(log_lik, np.log(1e-3))


def test_likelihood_names_bad_argument():
    with pytest.raises(ValueError, match="cand_prior"):
        sir.candidate_log_likelihood(np.zeros((2, 3)), np.zeros((3, 3)), np.zeros(2), 0.1)
    with pytest.raises(ValueError, match="sigma_m"):
        sir.candidate_log_likelihood(np.zeros((2, 3)), np.zeros((1, 3)), np.ones(1), 0.0)


def test_prediction_is_constant_velocity_without_noise(rng):
    s = np.array([[1.0, 2.0, 1.0, 0.5, -1.0, 0.0]])
    out = sir.predict_constant_velocity(s, 0.0, 0.2, rng)
    assert np.allclose(out, [[1.1, 1.8, 1.0, 0.5, -1.0, 0.0]])
    fast = sir.predict_constant_velocity(
        np.array([[0, 0, 0, 10.0, 0, 0]]), 0.0, 0.1, rng, max_speed_mps=4.0
    )
    assert np.allclose(fast[0, 3:], [4.0, 0, 0])


def test_prediction_noise_has_the_model_variance(rng):
    s = np.zeros((20000, 6))
    out = sir.predict_constant_velocity(s, 6.0, 0.1, rng)
    # p = a dt^2 / 2, v = a dt with a ~ N(0, 6^2)
    assert np.std(out[:, 0]) == pytest.approx(6.0 * 0.01 / 2, rel=0.05)
    assert np.std(out[:, 3]) == pytest.approx(0.6, rel=0.05)


def test_velocity_reset_forgets_the_old_velocity(rng):
    """The stop-and-go component: a fresh velocity around zero whatever the old one was, and
    the position moved by it over the step (a particle that lands d away carries d / dt)."""
    s = np.tile([1.0, 2.0, 1.0, 3.0, -2.0, 0.0], (20000, 1))
    out = sir.predict_velocity_reset(s, 0.8, 0.1, rng)
    assert np.allclose(out[:, 3:].mean(axis=0), 0.0, atol=0.02)
    assert np.allclose(out[:, 3:].std(axis=0), 0.8, rtol=0.05)
    assert np.allclose(out[:, :3], s[:, :3] + out[:, 3:] * 0.1)
    jittered = sir.predict_velocity_reset(s, 0.0, 0.1, rng, jitter_m=0.01)
    assert np.allclose(jittered[:, 3:], 0.0)
    assert np.std(jittered[:, 0]) == pytest.approx(0.01, rel=0.05)
    with pytest.raises(ValueError, match="dt_s"):
        sir.predict_velocity_reset(s, 0.8, -0.1, rng)


def test_block_mean_cov_matches_numpy(rng):
    pts = rng.normal(size=(12, 3))
    w = rng.random(12)
    starts = np.array([0, 5])
    owner = sir.block_owner(starts, 12)
    log_w = np.log(w / np.bincount(owner, weights=w)[owner])
    mean, cov = sir.block_mean_cov(pts, log_w, starts)
    for b, sl in enumerate((slice(0, 5), slice(5, 12))):
        assert np.allclose(mean[b], np.average(pts[sl], axis=0, weights=w[sl]))
        assert np.allclose(cov[b], np.cov(pts[sl].T, aweights=w[sl], bias=True))


def test_claim_shares_split_by_closeness_and_only_among_allowed_targets():
    means = np.array([[0.0, 0, 0], [0.2, 0, 0]])
    cands = np.array([[0.01, 0, 0], [0.1, 0, 0], [0.19, 0, 0]])
    shares = sir.claim_shares(means, np.full(2, 1e-4), cands, 0.03)
    np.testing.assert_allclose(shares.sum(axis=0), 1.0)
    assert shares[0, 0] > 0.99 and shares[1, 2] > 0.99
    np.testing.assert_allclose(shares[:, 1], 0.5)
    # the nearer target may not take the first candidate (a crown head, target 0 a hand):
    # the other takes all of it, however far; a candidate nobody may take is nobody's
    allowed = np.array([[False, True, False], [True, True, False]])
    shares = sir.claim_shares(means, np.full(2, 1e-4), cands, 0.03, allowed)
    np.testing.assert_allclose(shares[:, 0], [0.0, 1.0])
    np.testing.assert_allclose(shares[:, 1], 0.5)
    np.testing.assert_array_equal(shares[:, 2], 0.0)
