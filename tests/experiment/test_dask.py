"""The same sweep through a Dask cluster gives the same results as the local pool."""

from __future__ import annotations

from pathlib import Path

import pytest

from mrcomm.experiment.runner import dask_executor, execute_sweep, plan_sweep, process_pool
from mrcomm.experiment.schema import load_experiment
from tests import needs
from tests.experiment.helpers import MINI, snapshot, write_schema

distributed = needs.module("dask.distributed")


def test_dask_cluster_and_local_pool_store_identical_results(tmp_path: Path) -> None:
    exp = load_experiment(write_schema(tmp_path, MINI.replace("max_time: 30", "max_time: 20")))
    local_db, dask_db = tmp_path / "local.duckdb", tmp_path / "dask.duckdb"
    with process_pool(2) as pool:
        local = execute_sweep(plan_sweep(exp, local_db, repetitions=1), pool, max_in_flight=4)
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
    ) as cluster:
        # Through the scheduler's address, as `mrcomm sweep --scheduler` connects.
        executor, in_flight, close = dask_executor(cluster.scheduler_address)
        try:
            remote = execute_sweep(
                plan_sweep(exp, dask_db, repetitions=1), executor, max_in_flight=in_flight
            )
        finally:
            close()
    assert in_flight == 4  # two per worker thread
    assert local.ok == remote.ok == 4 and local.failed == remote.failed == 0
    a, b = snapshot(local_db), snapshot(dask_db)
    assert len(a["runs"]) == 4 and len(a["intervals"]) > 0 and len(a["messages"]) > 0
    assert a == b


def test_an_unreachable_scheduler_is_bad_input() -> None:
    from mrcomm.errors import InputError

    with pytest.raises(InputError, match=r"cannot reach the Dask scheduler tcp://127\.0\.0\.1:9"):
        dask_executor("tcp://127.0.0.1:9", timeout_s=0.5)
