"""A study's size and executor options are refused in the words of whoever gave them:
``hdsim.sobol(n=100)`` and ``run_study`` name their keywords, ``hdsim sobol --n 100`` its
options (docs/sensitivity.md §9), and a suggested N is one the study accepts.

Every case is refused before a simulation runs: a fraction of a second.
"""

from __future__ import annotations

import re

import pytest

import hdsim
from hdsim.errors import InputError
from hdsim.sensitivity import run_study
from hdsim.sensitivity.design import check_sizes
from hdsim.sensitivity.functions import Linear
from hdsim.sensitivity.problem import CLI_WORDING
from hdsim.sensitivity.store import open_store

#: keyword arguments of the Python API -> the start of their refusal
PYTHON_CASES = [
    (dict(n=100), r"^n must be a power of 2 .* got 100; nearest: 128$"),
    (dict(n=0), r"^n must be a power of 2 .* got 0; nearest: 16$"),
    (dict(n=8), r"^n=8 is too small for replicates=4: need n >= 16"),
    (dict(replicates=3), r"^replicates must be a power of 2 and at least 2, got 3$"),
    (dict(workers=0), r"^workers must be a whole number, at least 1, got 0$"),
    (dict(n=64, target_width=0.0), r"^target_width must be > 0"),
    (dict(executor="nowhere"), r"^executor must be 'local' or 'dask://HOST:PORT'"),
    (dict(resume=True), r"^resume=True needs out: the study file to continue$"),  # was ignored
]


@pytest.mark.parametrize("kwargs, message", PYTHON_CASES)
def test_hdsim_sobol_names_its_keywords(kwargs, message):
    with pytest.raises(InputError) as error:
        hdsim.sobol("CSG-25-100", ["h_pz"], "lost_motion_arcmin", progress=False, **{"workers": 1, **kwargs})
    assert re.search(message, str(error.value)), str(error.value)
    assert "--" not in str(error.value)


@pytest.mark.parametrize("kwargs, message", [(dict(n=100), r"^n must"), (dict(workers=0), r"^workers must"),
                                             (dict(n=16, replicates=1), r"^replicates must")])
def test_the_generic_engine_names_its_keywords(kwargs, message):
    f = Linear()
    with pytest.raises(InputError, match=message):
        run_study(f, f.problem(), **{"n": 16, "progress": False, **kwargs})


def test_an_existing_study_file_is_refused_in_python_words(tmp_path):
    definition = {"problem": Linear().problem().to_dict(), "seed": 0, "second_order": False, "replicates": 4,
                  "model": {}}
    (tmp_path / "s.h5").write_bytes(b"")  # refused for existing, before it is read
    with pytest.raises(InputError, match=r"pass resume=True to continue it, or choose another out$"):
        open_store(definition, 16, tmp_path / "s.h5")
    with pytest.raises(InputError, match=r"pass --resume to continue it, or choose another --out$"):
        open_store(definition, 16, tmp_path / "s.h5", wording=CLI_WORDING)


def test_the_command_line_keeps_its_options(tmp_path):
    with pytest.raises(InputError, match=r"^--n must be a power of 2 .* nearest: 128$"):
        check_sizes(100, 4, CLI_WORDING)
    with pytest.raises(InputError, match=r"^--n 8 is too small for --replicates 4"):
        check_sizes(8, 4, CLI_WORDING)
    f = Linear()
    with pytest.raises(InputError, match=r"^--workers must"):
        run_study(f, f.problem(), 16, workers=0, progress=False, wording=CLI_WORDING)


@pytest.mark.parametrize("replicates", [2, 4, 8, 32])
@pytest.mark.parametrize("n", [0, 1, 3, 5, 7, 100, 1000, 3000, 2.5, "many"])
def test_the_suggested_n_is_valid(n, replicates):
    with pytest.raises(InputError) as error:
        check_sizes(n, replicates)
    nearest = int(re.search(r"(?:nearest: |need n >= )(\d+)", str(error.value)).group(1))
    assert check_sizes(nearest, replicates) == nearest // replicates
