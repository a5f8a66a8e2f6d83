"""The same study on a Dask LocalCluster gives the same indices as locally."""

import json

import numpy as np
import pytest

from hdsim.cli import main
from hdsim.sensitivity import GFunction, run_study

distributed = pytest.importorskip("distributed")

KEYS = ("S1", "ST", "S1_conf", "ST_conf", "S1_conf_replicates", "ST_conf_replicates")


@pytest.fixture(scope="module")
def cluster():
    # Two single-thread workers in this process; tcp so the CLI can connect by address.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  protocol="tcp", dashboard_address=None) as c:
        yield c


def test_dask_executor_matches_local(cluster):
    g = GFunction()
    local = run_study(g, g.problem(), 256, seed=3, workers=1, progress=False).analysis
    with distributed.Client(cluster) as client:
        remote = run_study(g, g.problem(), 256, seed=3, chunksize=37, progress=False,
                           executor=client.get_executor(pure=False)).analysis
    for key in KEYS:
        np.testing.assert_array_equal(local[key], remote[key])


def test_cli_dask_address_matches_local(cluster, capsys):
    argv = ["sobol", "--function", "ishigami", "--n", "256", "--seed", "1", "--json"]
    assert main(argv + ["--workers", "1"]) == 0
    local = json.loads(capsys.readouterr().out)
    address = cluster.scheduler_address.removeprefix("tcp://")
    assert main(argv + ["--executor", f"dask://{address}"]) == 0
    remote = json.loads(capsys.readouterr().out)
    for key in KEYS:
        assert remote[key] == local[key]
    assert remote["executor"].startswith("dask://")
