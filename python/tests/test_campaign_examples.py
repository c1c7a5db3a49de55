"""The campaign examples run as they are: the Slurm job-array scripts (on a
machine without sbatch they fly the shards here, then merge) give the
unsharded runs.csv byte for byte and resume by flying only the missing
shards; the Dask LocalCluster example gives the local call's rows."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SLURM = REPO / "examples" / "slurm"


def campaign(cli: Path, tmp_path: Path) -> str:
    env = dict(os.environ, FTSMC_LOCAL="1", FTSMC=str(cli.resolve()), CONTROLLERS="ftaftsmc,pid")
    done = subprocess.run(
        ["bash", str(SLURM / "campaign.sh"), "paper-scenario-2", "5", "3", "camp"],
        capture_output=True,
        text=True,
        env=env,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stdout


def test_slurm_array_scripts_merge_into_the_unsharded_result_and_resume(cli: Path, tmp_path: Path) -> None:
    if shutil.which("bash") is None:
        pytest.skip("no bash")
    campaign(cli, tmp_path)
    subprocess.run(
        [str(cli.resolve()), "montecarlo", "paper-scenario-2", "--runs", "5", "-c", "ftaftsmc,pid", "--no-figures", "--out", "whole"],
        check=True,
        capture_output=True,
        cwd=tmp_path,
    )
    merged = tmp_path / "camp" / "paper-scenario-2" / "runs.csv"
    assert merged.read_bytes() == (tmp_path / "whole" / "paper-scenario-2" / "runs.csv").read_bytes()

    # A failed shard: only it is flown again, then the merge succeeds.
    shards = tmp_path / "camp" / "shards"
    shutil.rmtree(shards / "paper-scenario-2-shard-2-of-3")
    merged.unlink()
    out = campaign(cli, tmp_path)
    assert out.count("skipped") == 2 and "shard 2/3" in out and "merged from 3 shards" in out, out
    assert merged.read_bytes() == (tmp_path / "whole" / "paper-scenario-2" / "runs.csv").read_bytes()


def test_dask_local_cluster_example(tmp_path: Path) -> None:
    pytest.importorskip("distributed")
    done = subprocess.run(
        [sys.executable, str(REPO / "examples" / "python" / "dask_local.py"), "--runs", "8", "--workers", "2"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert "rows identical to the local call" in done.stdout, done.stdout


def test_bad_shard_arguments_are_refused_with_their_value() -> None:
    import ftsmc
    from ftsmc import _ftsmc

    s = ftsmc.Scenario.builtin("paper-scenario-2")
    with pytest.raises(ValueError, match="needs a Dask client"):
        ftsmc.montecarlo(s, 4, shards=2)
    with pytest.raises(ValueError, match=r"run_range \(3, 9\).*runs \(4\)"):
        _ftsmc.montecarlo_columns(s, 4, None, None, 1, (3, 9))
    # A run range flies exactly those rows of the whole batch.
    whole = ftsmc.montecarlo(s, 4, controllers=["pid"], threads=1)
    names, columns = _ftsmc.montecarlo_columns(s, 4, None, ["pid"], 1, (1, 3))
    assert list(columns[0]) == [1, 2]
    for name, column in zip(names, columns):
        expected = list(whole[name].iloc[1:3])
        got = list(column)
        assert [str(v) for v in got] == [str(v) for v in expected], name
