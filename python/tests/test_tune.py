"""ftsmc.tune: the ``ftsmc tune`` search from Python, thread-independent,
with a tuned TOML that loads back to the tuned scenario."""

from __future__ import annotations

from pathlib import Path

import pytest

import ftsmc


# The start and two generations of 4 samples and their mean, the second
# with the anchor beside them, 2 flights each.
BUDGET = 2 * (1 + 5 + 6)


def tiny() -> ftsmc.Scenario:
    return ftsmc.Scenario.builtin("realistic-scenario-2").with_overrides(
        {"duration": 1.5, "tune": {"runs": 2, "validation_runs": 3, "population": 4}}
    )


def test_a_tiny_tune_is_the_same_on_one_and_two_threads(tmp_path: Path) -> None:
    s = tiny()
    one = ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=1, extends="base.toml")
    two = ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=2, extends="base.toml")
    assert one.toml == two.toml
    assert one.scenario == two.scenario
    assert len(one.summary["history"]) == 1 + 5 + 6
    assert one.summary["held_out"]["tuned"]["runs"] == 3
    # The tuned file extends the input and loads back to the tuned gains.
    (tmp_path / "base.toml").write_text(s.to_toml())
    (tmp_path / "tuned.toml").write_text(one.toml)
    loaded = ftsmc.Scenario.from_file(tmp_path / "tuned.toml")
    assert loaded == one.scenario.with_overrides({"name": loaded.name})


def test_a_vehicle_set_by_with_overrides_travels_with_the_tuned_toml(tmp_path: Path) -> None:
    s = ftsmc.Scenario.builtin("realistic-calm-1").with_overrides(
        {"vehicle.preset": "crazyflie-2", "duration": 1.5, "tune": {"runs": 2, "validation_runs": 3, "population": 4}}
    )
    assert s.name == "realistic-calm-1-crazyflie-2"
    tuned = ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=1, extends="realistic-calm-1")
    assert 'extends = "realistic-calm-1"' in tuned.toml and 'preset = "crazyflie-2"' in tuned.toml
    (tmp_path / "pid.tuned.toml").write_text(tuned.toml)
    loaded = ftsmc.Scenario.from_file(tmp_path / "pid.tuned.toml")
    assert loaded == tuned.scenario.with_overrides({"name": loaded.name})
    assert "improved_reason" in tuned.summary


def test_bad_input_raises_value_error() -> None:
    with pytest.raises(ValueError, match="unknown controller"):
        ftsmc.tune(tiny(), "pidd", budget=100)
    with pytest.raises(ValueError, match="budget"):
        ftsmc.tune(tiny(), "pid", budget=3)
    with pytest.raises(ValueError, match="tune.sigma"):
        tiny().with_overrides({"tune.sigma": 2.0})


def test_a_tune_through_dask_equals_the_local_tune() -> None:
    distributed = pytest.importorskip("distributed")
    import logging

    s = tiny()
    local = ftsmc.tune(s, "tsm-sta", budget=BUDGET, seed=3, threads=1, extends="base.toml")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None, silence_logs=logging.CRITICAL
    )
    client = distributed.Client(cluster)
    try:
        remote = ftsmc.tune(s, "tsm-sta", budget=BUDGET, seed=3, extends="base.toml", client=client)
        batched = ftsmc.tune(s, "tsm-sta", budget=BUDGET, seed=3, extends="base.toml", client=client, batch=3)
    finally:
        client.close()
        cluster.close()
    for r in (remote, batched):
        assert r.toml == local.toml
        assert r.scenario == local.scenario
        # NaN statistics (no completed run) are None in the JSON: equal either way.
        assert r.summary == local.summary
    with pytest.raises(ValueError, match="batch"):
        ftsmc.tune(s, "tsm-sta", budget=BUDGET, client=object(), batch=0)


def test_the_dask_objective_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match="unknown controller"):
        ftsmc._ftsmc.tune_evaluate([tiny().to_toml()], "pidd", 1, [0])
    with pytest.raises(ValueError, match="candidate 0"):
        ftsmc._ftsmc.tune_evaluate(["duration = -1"], "pid", 1, [0])
    stats = ftsmc._ftsmc.tune_evaluate([tiny().to_toml()], "pid", 3, [0, 1])
    # One candidate, its 14 statistics (OutcomeStats::VALUES: flights first,
    # the robustness margin's mean shortfall among them).
    assert len(stats) == 1 and len(stats[0]) == 14 and stats[0][0] == 2


@pytest.mark.parametrize("key", ["seed", "duration", "no_such_key"])
def test_only_declared_gains_are_tunable(key: str) -> None:
    extra = {"tune": {"runs": 2, "population": 4, "extra": [{"key": key, "low": 1.0, "high": 100.0}]}}
    with pytest.raises(ValueError, match=f'tune.extra\\[0\\].key.*"{key}"'):
        ftsmc.tune(tiny().with_overrides(extra), "pid", budget=5)
    # A gain of the controller's own section is accepted.
    gain = {"tune": {"extra": [{"key": "pid.rate_p.0", "low": 0.01, "high": 1.0}]}}
    assert tiny().with_overrides(gain).to_toml()


def test_a_tune_for_a_mission_states_it_in_the_tuned_file(tmp_path: Path) -> None:
    s = tiny().with_overrides({"duration": 6.0})
    hover = ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=2, mission="hover")
    assert 'mission = "hover"' in hover.toml
    (tmp_path / "tuned.toml").write_text(hover.toml)
    loaded = ftsmc.Scenario.from_file(tmp_path / "tuned.toml")
    assert loaded.tune_mission == "hover"
    assert hover.scenario.tune_mission == "hover"
    # steps (the default) writes the file of a tune without a mission.
    plain = ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=2)
    assert ftsmc.tune(s, "pid", budget=BUDGET, seed=3, threads=2, mission="steps").toml == plain.toml
    assert "mission" not in plain.toml and plain.scenario.tune_mission is None
    with pytest.raises(ValueError, match='mission = "eight" is invalid \\(expected one of steps, hover'):
        ftsmc.tune(s, "pid", budget=BUDGET, mission="eight")
