"""``ftsmc.falsify`` and ``ftsmc.failure_probability``: the worst case found replays to its margin."""

import math

import pytest

import ftsmc

SHORT = """
extends = "realistic-breeze-1"
name = "short"
duration = 3.0
[envelope]
settle_after = 1.5
max_position_error = 1.5
[falsify]
gusts = 1
gust_onset = { low = 0.5, high = 2.5 }
gust_length = { low = 0.3, high = 1.5 }
gust_amplitude = { low = 0.0, high = 3.0, nominal = { mean = 0.0, std = 1.0 } }
gust_direction = { low = -180.0, high = 180.0 }
"""


def test_falsify_finds_a_worst_case_that_replays_bit_for_bit() -> None:
    s = ftsmc.Scenario.from_toml(SHORT)
    r = ftsmc.falsify(s, "pid", budget=10, seed=2, threads=1)
    # The rung's own mean-wind bounds are inherited; the gust's are this file's.
    gust = ["gust_onset[0]", "gust_length[0]", "gust_amplitude[0]", "gust_direction[0]"]
    assert r["parameters"] == ["wind_speed", "wind_direction", *gust]
    assert len(r["falsify"]["history"]) == 10 and len(r["random"]["history"]) == 10
    lowest = r["falsify"]["lowest_margin"]
    assert lowest == min(h["margin"] for h in r["falsify"]["history"])
    worst = ftsmc.Scenario.from_toml(r["worst_toml"])
    run = ftsmc.simulate(worst, "pid")
    assert run.metrics["margin"]["value"] == lowest
    assert r == ftsmc.falsify(s, "pid", budget=10, seed=2, threads=2)


def test_failure_probability_has_an_interval_and_bad_input_is_a_value_error() -> None:
    s = ftsmc.Scenario.from_toml(SHORT)
    e = ftsmc.failure_probability(s, "pid", budget=40, seed=1, threads=2)
    assert 0.0 <= e["lo"] <= e["p"] <= e["hi"] and e["flights"] == 40 and e["confidence"] == 0.95
    assert math.isfinite(e["hi"])
    with pytest.raises(ValueError, match="budget = 0"):
        ftsmc.falsify(s, "pid", budget=0)
    with pytest.raises(ValueError, match=r"\[falsify\]"):
        ftsmc.falsify(ftsmc.Scenario.builtin("paper-scenario-1"), "pid")
