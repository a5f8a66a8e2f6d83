"""`hdsim.sobol` takes typed bounds and words its errors as Python does; only the CLI parses text.

Every case here is refused (or its problem built) before a simulation runs, so the file
takes a fraction of a second.
"""

from __future__ import annotations

import math

import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.sensitivity.api import study_bounds
from hdsim.sensitivity.models import from_unit
from hdsim.sensitivity.problem import PYTHON_WORDING, bounds_pair, parse_bounds_options

OUTPUT = "lost_motion_arcmin"


@pytest.fixture(scope="module")
def drive():
    return hdsim.load_unit("CSG-25-100")


def test_a_mapping_of_typed_bounds_is_the_study(drive):
    names, bounds = study_bounds({"h_pz": (0.5e-3, 0.7e-3), "input_friction.viscous": None, "h_c": [5e-4, 7e-4]})
    assert names == ["h_pz", "input_friction.viscous", "h_c"]
    assert bounds == {"h_pz": (0.5e-3, 0.7e-3), "h_c": (5e-4, 7e-4)}  # None: within the range
    assert study_bounds("h_pz, h_c", {"h_c": (5e-4, 7e-4)}) == (["h_pz", "h_c"], {"h_c": (5e-4, 7e-4)})


def test_the_cli_text_and_the_typed_bounds_build_the_same_problem():
    typed = from_unit("CSG-25-100", ["h_pz", "h_c"], OUTPUT, None, 0.1, {"h_pz": (0.5e-3, 0.7e-3)}, {},
                      wording=PYTHON_WORDING)[1]
    parsed = from_unit("CSG-25-100", ["h_pz", "h_c"], OUTPUT, None, 0.1,
                       parse_bounds_options(["h_pz=0.5e-3:0.7e-3"]), {})[1]
    assert typed == parsed and typed.bounds[0] == (0.5e-3, 0.7e-3)


@pytest.mark.parametrize("names, bound", [(["h_pz", "h_c"], "flexspline.h_pz"),
                                          (["flexspline.h_pz", "h_c"], "h_pz")])
def test_a_parameter_is_one_whether_named_short_or_dotted(names, bound):
    """``h_pz`` in --params and ``flexspline.h_pz`` in --bounds (or the other way round) had
    been refused as a parameter the study does not vary."""
    problem = from_unit("CSG-25-100", names, OUTPUT, None, 0.1, {bound: (0.5e-3, 0.7e-3)},
                        {bound: "unif"})[1]
    assert list(problem.names) == names and problem.bounds[0] == (0.5e-3, 0.7e-3)


@pytest.mark.parametrize("value", ["0.5e-3:0.7e-3", (0.7e-3, 0.5e-3), (1e-3, 1e-3), (1e-3,), (1e-3, 2e-3, 3e-3),
                                   (1e-3, math.nan), (-math.inf, 1.0), (True, 2.0), ("a", "b"), 0.5e-3, None])
def test_bounds_that_are_not_low_high_pairs_are_refused_in_python_words(value):
    with pytest.raises(InputError) as err:
        bounds_pair("h_pz", value)
    assert str(err.value) == f"bounds for 'h_pz' must be (low, high) with low < high, got {value!r}"


@pytest.mark.parametrize("params, kwargs, message", [
    (["h_pz", "input_friction.nope"], {}, "unknown parameter 'input_friction.nope'; did you mean input_friction."),
    (["h_pz", "nope"], {}, "unknown parameter 'nope'; known: "),
    ({"h_pz": "0.5e-3:0.7e-3"}, {}, "bounds for 'h_pz' must be (low, high) with low < high, got '0.5e-3:0.7e-3'"),
    ({"h_pz": (0.7e-3, 0.5e-3)}, {}, "bounds for 'h_pz' must be (low, high) with low < high"),
    (["h_pz"], {"bounds": {"h_pz": (0.7e-3, 0.5e-3)}}, "bounds for 'h_pz' must be (low, high) with low < high"),
    (["h_pz"], {"bounds": {"h_c": (5e-4, 7e-4)}}, "unknown parameter 'h_c' in bounds: the study varies h_pz"),
    ({"h_pz": (5e-4, 7e-4)}, {"bounds": {"h_pz": (5e-4, 7e-4)}}, "bounds for 'h_pz' are given twice"),
    (["h_pz"], {"range": None}, "no bounds for 'h_pz': give range=FRACTION or bounds={'h_pz': (low, high)}"),
    (["h_pz"], {"range": "10"}, "range must be a fraction in (0, 10)"),
    (["h_pz"], {"range": -0.1}, "range must be a fraction in (0, 10)"),
    (["h_pz"], {"range": True}, "range must be a fraction in (0, 10)"),
    (["h_pz"], {"dists": {"h_c": "unif"}}, "unknown parameter 'h_c' in dists: the study varies h_pz"),
    (["h_pz"], {"dists": {"h_pz": "norm"}, "bounds": {"h_pz": (5e-4, 7e-4)}},
     "'h_pz' is normal: give dists={'h_pz': 'norm:MEAN:SD'} instead of bounds"),
    # a normal input with its numbers and bounds: the bounds had been dropped without a word
    (["h_pz"], {"dists": {"h_pz": "norm:6e-4:2e-5"}, "bounds": {"h_pz": (5e-4, 7e-4)}},
     "'h_pz' is given both dists={'h_pz': 'norm:MEAN:SD'} and bounds: a normal input has no bounds"),
    ([], {}, "sobol needs at least one parameter"),
    # values that contradict each other: the first breakpoint above the second (it ran)
    (["hardening.T1"], {"bounds": {"hardening.T1": (10.0, 70.0)}},
     "the range of hardening.T1 reaches 70, a drive the model refuses: hardening.T1 = 70 must be below"),
])
def test_python_errors_name_python_arguments_not_cli_options(drive, params, kwargs, message):
    with pytest.raises(InputError) as err:
        hdsim.sobol(drive, params, OUTPUT, n=8, replicates=2, workers=1, progress=False, **kwargs)
    text = str(err.value)
    assert message in text and "\n" not in text
    assert "--" not in text  # no command-line option in a Python message


@pytest.mark.parametrize("bounds, fragment", [
    (["h_pz=0.7e-3:0.5e-3"], "lo < hi"),
    (["h_pz=thin:0.7e-3"], "LO:HI"),
    (["h_c=0.5e-3:0.7e-3"], "unknown parameter in --bounds"),
])
def test_the_cli_keeps_its_option_words(cli, bounds, fragment):
    code, out, err = cli("sobol", "--unit", "CSG-25-100", "--params", "h_pz", "--output", OUTPUT,
                         "--bounds", *bounds, "--json")
    lines = err.strip().splitlines()
    assert code == 2 and out == "" and len(lines) == 1 and fragment in lines[0], err


@pytest.mark.parametrize("params, options, message", [
    # found by a tester: each ran, and its indices described something else than was asked
    (["h_pz", "flexspline.h_pz"], {}, r"parameter flexspline.h_pz is named twice \('h_pz', 'flexspline.h_pz'\)"),
    ({"h_pz": None, "h_c": (-0.7e-3, 0.7e-3)}, {}, r"the range of h_c reaches -0.0007, a drive the model refuses"),
    (["h_pz"], {"seed": -1}, "seed must be a whole number, 0 or more"),
    (["h_pz"], {"seed": "a"}, "seed must be a whole number, 0 or more"),
])
def test_a_study_that_would_not_be_the_one_asked_for_is_refused_before_it_runs(params, options, message, monkeypatch):
    from hdsim.sensitivity import study

    monkeypatch.setattr(study, "evaluate", lambda *a, **k: pytest.fail("the study ran"), raising=False)
    with pytest.raises(InputError, match=message):
        hdsim.sobol("CSG-25-100", params, "lost_motion_arcmin", range=0.1, n=16, **options)


@pytest.mark.parametrize("h_p, refused", [
    # every corner builds; the end h_pz = 0.3 mm had been tried with the nominal undercut, 0.3175 mm,
    # which lies outside the undercut's own range
    ((0.1e-3, 0.25e-3), False),
    ((0.25e-3, 0.5e-3), False),  # the end h_pz = 0.3 mm builds with the thinner undercuts
    ((0.35e-3, 0.5e-3), True),   # no undercut in its range is thinner than 0.3 mm: no row builds
])
def test_a_range_end_is_refused_only_when_no_row_of_the_box_builds_it(h_p, refused):
    bounds = {"h_pz": (0.3e-3, 1.2e-3), "h_p": h_p}
    if refused:
        with pytest.raises(InputError, match=r"the range of h_pz reaches 0.0003, a drive the model refuses: "
                                             r"flexspline geometry: undercut depth h_p = 0.35 mm"):
            from_unit("CSG-25-100", ["h_pz", "h_p"], OUTPUT, bounds=bounds)
    else:
        assert from_unit("CSG-25-100", ["h_pz", "h_p"], OUTPUT, bounds=bounds)[1].bounds[1] == h_p


def test_the_files_beside_the_study_file_are_checked_before_the_study(tmp_path, cli):
    """With --out s.h5 the summary s.json goes beside it: a folder of that name had failed the
    finished study as an internal error, its figures left without their summary."""
    (tmp_path / "s.json").mkdir()
    code, _, err = cli("sobol", "--function", "ishigami", "--n", "64", "--out", str(tmp_path / "s.h5"), cwd=tmp_path)
    assert code == 2 and "s.json is a folder" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.json"]


def _fails_above_a_quarter(X):
    """A model that fails on most of its box (module level: it must pickle)."""
    import numpy as np

    X = np.asarray(X)
    if np.any(X[:, 0] > 0.25):
        raise RuntimeError("too big")
    return X[:, 0] + X[:, 1]


def test_a_study_left_with_too_few_blocks_says_its_failures_before_the_refusal():
    """'see the failures above' had come with no failure above: they were listed only after a
    study that could be analysed."""
    from hdsim.sensitivity.problem import Problem
    from hdsim.sensitivity.study import run_study

    said = []
    problem = Problem(names=("a", "b"), bounds=((0.0, 1.0), (0.0, 1.0)), dists=("unif", "unif"))
    with pytest.raises(InputError, match="see the failures above"):
        run_study(_fails_above_a_quarter, problem, 16, workers=1, log=said.append)
    assert any("failed: RuntimeError: too big" in line for line in said)


def test_a_study_resumed_with_its_default_scenario_named_is_the_same_study(tmp_path):
    """Started without a scenario and resumed with the built-in one it ran named, the study was
    refused as another (the same fingerprint, 'scenario' null against 'lost_motion')."""
    out = tmp_path / "s.h5"
    first = hdsim.sobol("CSG-25-100", ["h_pz"], "lost_motion_arcmin", range=0.1, n=16, out=out, workers=1)
    again = hdsim.sobol("CSG-25-100", ["h_pz"], "lost_motion_arcmin", range=0.1, n=16, out=out, resume=True,
                        scenario="lost_motion", workers=1)
    assert again.evaluated_now == 0 and list(again.analysis["ST"]) == list(first.analysis["ST"])
    changed = hdsim.load_scenario("lost_motion").with_updates({"load.rate": 0.08})
    with pytest.raises(InputError, match="different study"):
        hdsim.sobol("CSG-25-100", ["h_pz"], "lost_motion_arcmin", range=0.1, n=16, out=out, resume=True,
                    scenario=changed, workers=1)
