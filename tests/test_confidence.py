"""The block bootstrap and the loo_compare-style table against hand computations."""

from __future__ import annotations

import math

import numpy as np
import pytest

from hdsim.identification.confidence import block_labels, block_sums, comparison_table, resample_counts


def test_block_labels_follow_the_starts():
    assert block_labels(10, [0, 3, 7]).tolist() == [0, 0, 0, 1, 1, 1, 1, 2, 2, 2]
    assert block_labels(4, [2, 0]).tolist() == [0, 0, 1, 1]  # unsorted starts


def test_resamples_draw_every_block_with_replacement():
    counts = resample_counts(7, resamples=4000, seed=3)
    assert counts.shape == (4000, 7) and np.all(counts.sum(axis=1) == 7)
    # a block's count in a resample of B draws is Binomial(B, 1/B): mean 1, variance 1 − 1/B
    assert counts.mean() == pytest.approx(1.0, abs=0.02)
    assert counts.var() == pytest.approx(1 - 1 / 7, rel=0.05)


def test_block_sums_split_the_holdout_by_fold():
    labels = np.array([0, 0, 1, 1, 1])
    fit = np.array([1.0, 2.0, 3.0, 0.0, 1.0])
    holdout = np.array([2.0, 0.0, 1.0, 1.0, 3.0])
    fold = np.array([0, 1, 1, 0, 1])
    s = block_sums(labels, 2, fit, holdout, fold)
    assert s.fit.tolist() == [5.0, 10.0]
    assert s.holdout.tolist() == [4.0, 11.0]
    assert s.holdout_by_fold.tolist() == [[4.0, 1.0], [0.0, 10.0]]


def test_comparison_table_matches_the_gaussian_elpd_by_hand():
    rng = np.random.default_rng(0)
    labels = np.repeat(np.arange(8), 25)
    good = rng.normal(0.0, 1.0, labels.size)
    poor = good + rng.normal(0.0, 0.5, labels.size)
    rows = comparison_table(["poor", "good"], [poor, good], labels)
    assert [r["model"] for r in rows] == ["good", "poor"]
    var = np.mean(good**2)  # the best model's hold-out variance
    expected = -(np.sum(poor**2) - np.sum(good**2)) / (2 * var)
    assert rows[1]["elpd_diff"] == pytest.approx(expected, rel=1e-12)
    d = np.array([-(np.sum(poor[labels == b] ** 2) - np.sum(good[labels == b] ** 2)) / (2 * var) for b in range(8)])
    assert rows[1]["se_diff"] == pytest.approx(math.sqrt(8 * np.var(d, ddof=1)), rel=1e-12)
    assert rows[0]["elpd_diff"] == 0.0 and rows[0]["se_diff"] == 0.0
    assert rows[0]["elpd"] == pytest.approx(np.sum(-0.5 * np.log(2 * np.pi * var) - good**2 / (2 * var)))


def test_one_block_has_no_standard_error():
    rows = comparison_table(["a", "b"], [np.ones(5), 2 * np.ones(5)], np.zeros(5, dtype=int))
    assert rows[1]["se_diff"] is None
