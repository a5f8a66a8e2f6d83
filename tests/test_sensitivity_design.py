"""Design structure, row pairing, failed samples and problem parsing."""

import numpy as np
import pytest

from hdsim.errors import InputError
from hdsim.sensitivity import DesignError, GFunction, Ishigami, analyse, check_design, run_study
from hdsim.sensitivity.checks import consistency_checks
from hdsim.sensitivity.design import (check_sizes, fingerprint, replicate_seed,
                                      sample_replicate)
from hdsim.sensitivity.evaluate import evaluate
from hdsim.sensitivity.problem import build_problem, parse_assignments, parse_range

F = Ishigami()
P = F.problem()


def _design(n=256, R=4, second_order=False, seed=0):
    return np.concatenate([sample_replicate(P, n // R, replicate_seed(seed, r), second_order)
                           for r in range(R)])


def test_design_is_extensible_by_doubling():
    for so in (False, True):
        small, big = (sample_replicate(P, n, 11, so) for n in (64, 128))
        np.testing.assert_array_equal(small, big[:len(small)])


@pytest.mark.parametrize("second_order", [False, True])
def test_structure_check_passes_and_catches_tampered_rows(second_order):
    X = _design(second_order=second_order)
    check_design(X, 3, second_order)
    k = 8 if second_order else 5
    for row, col in ((k * 7 + 2, 1), (k * 3 + 1, 2)):  # AB_2's own column, AB_1's other column
        bad = X.copy()
        bad[row, col] += 1e-9
        with pytest.raises(DesignError, match=f"row {row}"):
            check_design(bad, 3, second_order)
    if second_order:  # a BA row
        bad = X.copy()
        bad[k * 5 + 4, 0] *= 1.0001
        with pytest.raises(DesignError, match="BA_1"):
            check_design(bad, 3, True)


def test_shuffled_outputs_are_caught_by_fingerprints():
    X = _design()
    ev = evaluate(F, X, workers=1, chunksize=40, progress=False)
    analyse(P, X, ev.y, second_order=False, replicates=4, key=ev.key)  # fine in order
    # Completion order: chunks come back permuted, outputs and keys together.
    order = np.random.default_rng(1).permutation(len(X) // 40)
    perm = np.concatenate([np.arange(c * 40, c * 40 + 40) for c in order])
    with pytest.raises(DesignError, match="matched to rows by index"):
        analyse(P, X, ev.y[perm], second_order=False, replicates=4, key=ev.key[perm])
    shifted = np.roll(np.arange(len(X)), 1)
    with pytest.raises(DesignError):
        analyse(P, X, ev.y[shifted], second_order=False, replicates=4, key=ev.key[shifted])


def test_unpaired_outputs_trip_the_consistency_flags():
    X = _design(1024)
    Y = F(X)[np.random.default_rng(0).permutation(len(X))]  # no keys: values only
    res = analyse(P, X, Y, second_order=False, replicates=4)
    checks = consistency_checks(res["S1"], res["ST"], res["S1_conf_replicates"],
                                res["ST_conf_replicates"], P.names)
    assert not checks["ok"] and checks["flags"]


def test_additive_but_total_differs_flag():
    checks = consistency_checks([0.5, 0.5], [0.5, 0.8], [0.01, 0.01], [0.01, 0.01])
    assert any("looks additive" in f for f in checks["flags"])
    assert not checks["ok"]


def test_an_additive_model_with_mispaired_rows_is_flagged():
    """Each f(A) filed with the next base point's AB and B rows: ΣS1 stays near 1, every
    ST grows far past its S1."""
    from hdsim.sensitivity import Linear

    f = Linear()
    X = np.concatenate([sample_replicate(f.problem(), 64, replicate_seed(0, r), False) for r in range(4)])
    blocks = f(X).reshape(-1, f.problem().num_vars + 2)
    blocks[:, 0] = np.roll(blocks[:, 0], 1)
    res = analyse(f.problem(), X, blocks.reshape(-1), second_order=False, replicates=4)
    checks = consistency_checks(res["S1"], res["ST"], res["S1_conf_replicates"], res["ST_conf_replicates"])
    assert any("looks additive" in flag for flag in checks["flags"]) and not checks["ok"]


@pytest.mark.parametrize("seed", range(6))
def test_a_noisy_study_of_a_model_with_interactions_is_no_broken_design(seed):
    """Ishigami (ΣS1 = 0.756) at N = 256: the replicate interval of ΣS1 reaches 1, and the
    flag had called the model additive and its design broken (seeds 0, 1, 2, 4, 5)."""
    X = _design(256, seed=seed)
    res = analyse(P, X, F(X), second_order=False, replicates=4)
    checks = consistency_checks(res["S1"], res["ST"], res["S1_conf_replicates"], res["ST_conf_replicates"])
    assert checks["flags"] == [] and checks["ok"]


class FailsOnOneRow:
    """Ishigami that raises on one chosen input row (or returns NaN)."""

    def __init__(self, row, nan=False):
        self.row, self.nan = np.asarray(row), nan

    def __call__(self, X):
        hit = np.all(X == self.row, axis=1)
        if hit.any() and not self.nan:
            raise RuntimeError("solver gave up")
        return np.where(hit, np.nan, F(X))


@pytest.mark.parametrize("nan", [False, True])
def test_failed_sample_drops_only_its_block(nan, capsys):
    n, R, k = 256, 4, 5
    X = _design(n, R)
    g = 2 * (n // R * k) + 7 * k + 2  # replicate 2, block 7, AB_2
    res = run_study(FailsOnOneRow(X[g], nan), P, n, workers=1, progress=False)
    assert [f["row"] for f in res.failures] == [g]
    assert res.failures[0]["replicate"] == 2 and res.failures[0]["block"] == 7
    assert res.failures[0]["params"]["x1"] == X[g, 0]
    assert res.analysis["blocks_dropped"] == 1 and res.analysis["blocks_used"] == n - 1
    err = capsys.readouterr().err
    assert f"sample {g}" in err and "dropped" in err
    # Same as analysing the intact outputs without that block.
    keep = np.ones(len(X), bool)
    keep[g - 2:g - 2 + k] = False
    Y = F(X)
    Y[~keep] = np.nan
    ref = analyse(P, X, Y, second_order=False, replicates=R)
    np.testing.assert_array_equal(res.analysis["S1"], ref["S1"])


def test_model_failing_everywhere_aborts():
    from hdsim.sensitivity import ModelError

    with pytest.raises(ModelError, match="failed on all"):
        evaluate(lambda X: np.full(len(X), np.nan), np.zeros((600, 2)), workers=1,
                 progress=False)


def test_fingerprint_changes_with_any_bit():
    X = _design(64)
    h = fingerprint(X)
    assert len(np.unique(h)) == len(X)
    Z = X.copy()
    Z[5, 2] = np.nextafter(Z[5, 2], 10)
    assert (fingerprint(Z) != h).sum() == 1


def test_sizes_and_problem_parsing():
    assert check_sizes(1024, 4) == 256
    for n in (1000, 0, 8):
        with pytest.raises(InputError):
            check_sizes(n, 4)
    assert parse_range("10%") == pytest.approx(0.1)
    p = build_problem(["a", "b", "c"], {"a": 2.0, "b": -1.0, "c": 5.0}, 0.1,
                      {"c": "1:9"}, {"b": "norm", "c": "logunif"})
    assert p.bounds[0] == pytest.approx((1.8, 2.2))
    assert p.bounds[1] == pytest.approx((-1.0, 0.1)) and p.dists[1] == "norm"
    assert p.bounds[2] == (1.0, 9.0) and p.dists[2] == "logunif"
    assert p.to_salib()["dists"] == ["unif", "norm", "logunif"]
    q = build_problem(["a"], dists={"a": "norm:2.5:0.1"})
    assert q.bounds == ((2.5, 0.1),) and q.variances()[0] == pytest.approx(0.01)
    bad = [dict(names=["a"], nominal={"a": 0.0}, range_frac=0.1),
           dict(names=["a"], bounds={"b": "1:2"}, range_frac=0.1, nominal={"a": 1}),
           dict(names=["a"], bounds={"a": "2:1"}),
           dict(names=["a"], bounds={"a": "x:1"}),
           dict(names=["a"], bounds={"a": "-1:1"}, dists={"a": "logunif"}),
           dict(names=["a"], dists={"a": "gamma"}, bounds={"a": "1:2"}),
           dict(names=["a"], dists={"a": "norm"}, bounds={"a": "1:2"}),
           dict(names=["a"], dists={"a": "norm:1:-2"}),
           dict(names=["a"])]
    for kw in bad:
        with pytest.raises(InputError):
            build_problem(**kw)
    for text in ("10", "ten%", "-5%"):
        with pytest.raises(InputError):
            parse_range(text)
    with pytest.raises(InputError):
        parse_assignments(["a:1:2"], "--bounds")


def test_gfunction_problem_and_local_pool_match_serial():
    g = GFunction()
    serial = run_study(g, g.problem(), 128, workers=1, progress=False).analysis
    pooled = run_study(g, g.problem(), 128, workers=2, chunksize=50, progress=False).analysis
    for key in ("S1", "ST", "S1_conf", "ST_conf", "S1_conf_replicates"):
        np.testing.assert_array_equal(serial[key], pooled[key])
