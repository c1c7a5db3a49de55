"""Monte Carlo on a Dask LocalCluster of two worker processes: the rows equal
the single-process call's, also when a worker is killed while flying."""

from __future__ import annotations

import logging
import math
import os
import signal
import threading
import time
from typing import Any, Dict, Iterator, List

import pandas
import pandas.testing
import pytest

import ftsmc
from ftsmc.dask import shard_ranges

distributed = pytest.importorskip("distributed")

SCENARIO = "paper-scenario-2"
CONTROLLERS = ["ftaftsmc"]


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        silence_logs=logging.CRITICAL,
    )
    c = distributed.Client(cluster)
    try:
        yield c
    finally:
        c.close()
        cluster.close()


def local(runs: int) -> pandas.DataFrame:
    return ftsmc.montecarlo(ftsmc.Scenario.builtin(SCENARIO), runs, controllers=CONTROLLERS)


def same_rows(a: pandas.DataFrame, b: pandas.DataFrame) -> None:
    pandas.testing.assert_frame_equal(a, b, check_exact=True)
    assert a.to_csv(index=False) == b.to_csv(index=False)


def test_shard_ranges_are_the_cli_blocks() -> None:
    assert shard_ranges(7, 3) == [(0, 2), (2, 4), (4, 7)]
    assert shard_ranges(5, 5) == [(k, k + 1) for k in range(5)]
    with pytest.raises(ValueError, match="between 1 and runs"):
        shard_ranges(3, 4)


def test_rows_equal_the_local_call(client: Any) -> None:
    scenario = ftsmc.Scenario.builtin(SCENARIO)
    # Two controllers, uneven shards, a master seed other than the scenario's.
    expected = ftsmc.montecarlo(scenario, 7, seed=11, controllers=["ftaftsmc", "pid"])
    got = ftsmc.montecarlo(scenario, 7, seed=11, controllers=["ftaftsmc", "pid"], client=client, shards=3)
    same_rows(expected, got)
    assert list(got["run"]) == [r for r in range(7) for _ in range(2)]


def test_a_worker_killed_mid_task_loses_and_repeats_nothing(client: Any) -> None:
    # Size the tasks from this machine's speed, so that each one flies for
    # about two seconds: long enough for the killer below to find a worker
    # mid-task on a fast machine, short enough for CI.
    shards = 4
    started = time.monotonic()
    local(2)
    per_run = max((time.monotonic() - started) / 2.0, 1e-3)
    runs = shards * min(max(6, math.ceil(2.0 / per_run)), 500)
    expected = local(runs)
    pids: Dict[str, int] = client.run(os.getpid)
    killed: List[str] = []
    done = threading.Event()

    def kill_a_busy_worker() -> None:
        # Wait until a worker has been flying a task for a moment, then SIGKILL it.
        deadline = time.monotonic() + 60.0
        busy_since: Dict[str, float] = {}
        while time.monotonic() < deadline and not done.is_set():
            for address, keys in client.processing().items():
                if keys and address in pids:
                    since = busy_since.setdefault(address, time.monotonic())
                    if time.monotonic() - since > 0.3:
                        os.kill(pids[address], signal.SIGKILL)
                        killed.append(address)
                        return
            time.sleep(0.02)

    killer = threading.Thread(target=kill_a_busy_worker)
    killer.start()
    try:
        got = ftsmc.montecarlo(
            ftsmc.Scenario.builtin(SCENARIO), runs, controllers=CONTROLLERS, client=client, shards=shards
        )
    finally:
        done.set()
        killer.join()
    assert killed, f"no worker was killed while flying ({runs} runs, {per_run:.3f} s a run): the test tested nothing"
    with pytest.raises(ProcessLookupError):
        os.kill(pids[killed[0]], 0)
    same_rows(expected, got)
