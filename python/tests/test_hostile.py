"""Hostile calls raise Python exceptions; they never kill the interpreter:
self-referencing or hugely nested overrides, huge dotted keys, Ctrl-C during
a flight or a batch, a Python controller handed to the Monte Carlo, seeds of
the full u64 range."""

from __future__ import annotations

import importlib
import os
import signal
import threading
import time
from typing import Any, Dict, Iterator

import pytest

import ftsmc


def test_a_self_referencing_dict_raises_value_error() -> None:
    d: Dict[str, Any] = {}
    d["self"] = d
    with pytest.raises(ValueError, match="deeper than"):
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"payload": d})


def test_nesting_fifteen_thousand_deep_raises_value_error() -> None:
    deep: Any = 1.0
    for _ in range(15_000):
        deep = [deep]
    with pytest.raises(ValueError, match="deeper than"):
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"payload.mass": deep})
    nested: Any = 1.0
    for _ in range(15_000):
        nested = {"a": nested}
    with pytest.raises(ValueError, match="deeper than"):
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"payload": nested})


def test_very_long_dotted_keys_raise_value_error() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-1")
    with pytest.raises(ValueError, match="at most 256 characters") as e:
        s.with_overrides({"a." * 500_000 + "b": 1.0})
    assert len(str(e.value)) < 400
    with pytest.raises(ValueError, match="16 parts"):
        s.with_overrides({".".join(["a"] * 40): 1.0})


def test_seeds_of_the_whole_u64_range_round_trip() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-1")
    for seed in (2**63, 2**64 - 1):
        t = s.with_overrides({"seed": seed})
        assert t.seed == seed
        assert ftsmc.Scenario.from_toml(t.to_toml()).seed == seed
    with pytest.raises(ValueError):
        s.with_overrides({"seed": 2**64})


def _interrupt_after(seconds: float) -> threading.Timer:
    """Send SIGINT to this process after `seconds` (as Ctrl-C would)."""
    timer = threading.Timer(seconds, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    return timer


@pytest.fixture(autouse=True)
def _python_default_ctrl_c() -> Iterator[None]:
    """Python's own SIGINT handler (KeyboardInterrupt) during each test, as
    in a user's session, whatever a library loaded by an earlier test
    installed; restored afterwards."""
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _long(scenario: str) -> ftsmc.Scenario:
    # Long enough that only Ctrl-C ends it within the test's bound, short
    # enough (2e7 steps) that a broken cancellation fails the test in
    # seconds instead of hanging the suite.
    return ftsmc.Scenario.builtin(scenario).with_overrides(
        {"duration": 2e4, "limits.max_steps": float("inf"), "simulation.record_rate": 0.0}
    )


def test_ctrl_c_stops_simulate_within_a_second() -> None:
    s = _long("paper-scenario-1")
    timer = _interrupt_after(0.5)
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        ftsmc.simulate(s, "pid")
    timer.join()
    assert time.monotonic() - started < 1.5


def test_ctrl_c_stops_montecarlo_within_a_second() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-2")
    timer = _interrupt_after(0.5)
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        # 1000 flights of 50 s: tens of seconds of work, so only Ctrl-C ends it
        # within the bound, and a bounded failure if cancellation breaks.
        ftsmc.montecarlo(s, 1_000, controllers=["pid"])
    timer.join()
    assert time.monotonic() - started < 1.5


def test_ctrl_c_stops_a_python_controller() -> None:
    class Hover:
        def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
            return ftsmc.Command(0.74 * 9.81, (0.0, 0.0, 0.0))

    s = _long("paper-scenario-1")
    timer = _interrupt_after(0.5)
    started = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        ftsmc.simulate(s, Hover())
    timer.join()
    assert time.monotonic() - started < 1.5


def test_montecarlo_with_a_python_controller_says_why_and_what_to_do() -> None:
    class Pd:
        def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
            return ftsmc.Command(0.74 * 9.81, (0.0, 0.0, 0.0))

    with pytest.raises(TypeError, match="built-in controllers by name.*got a Pd object.*ftsmc.simulate"):
        ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-2"), 2, controllers=[Pd()])  # type: ignore[list-item]


# ---- checks before allocations (limits off included) ----------------------

LIMITS_OFF = {
    "limits": {
        k: float("inf")
        for k in [
            "max_steps",
            "max_samples",
            "max_output_bytes",
            "max_flights",
            "max_sweep_points",
            "max_threads",
            "max_scenario_bytes",
        ]
    }
}


def _nonempty(e: BaseException) -> str:
    text = str(e)
    assert text.strip(), f"{type(e).__name__} without a message"
    assert len(text.splitlines()[0]) <= 300, text
    return text


def test_simulate_with_limits_off_is_bounded() -> None:
    with pytest.raises(ValueError) as e:
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({**LIMITS_OFF, "duration": 1e300})
    assert "hard bound" in _nonempty(e.value) and "max_steps" in str(e.value)


def test_montecarlo_with_limits_off_is_bounded() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-1").with_overrides(LIMITS_OFF)
    for runs in [10**12, 2**64 - 1]:
        with pytest.raises(ValueError) as e:
            ftsmc.montecarlo(s, runs=runs, progress=False)
        assert "hard bound" in _nonempty(e.value) and "max_flights" in str(e.value)
    with pytest.raises(ValueError) as e:
        ftsmc.montecarlo(s, runs=2, threads=100_000, progress=False)
    assert "max_threads" in _nonempty(e.value)


def test_montecarlo_without_controllers_is_refused() -> None:
    with pytest.raises(ValueError, match="controllers") as e:
        ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-1"), runs=2, controllers=[], progress=False)
    _nonempty(e.value)


def test_shards_are_capped_before_any_range_is_built() -> None:
    from ftsmc.dask import MAX_SHARDS, shard_ranges

    with pytest.raises(ValueError, match="MAX_SHARDS") as e:
        shard_ranges(10**9, 10**9)
    _nonempty(e.value)
    assert len(shard_ranges(10**9, MAX_SHARDS)) == MAX_SHARDS


def test_from_toml_has_the_cli_size_limit() -> None:
    text = 'name = "big"\n' + "# padding\n" * 120_000  # 1.2 MB
    with pytest.raises(ValueError, match="max_scenario_bytes") as e:
        ftsmc.Scenario.from_toml(text)
    _nonempty(e.value)


def test_an_unrecorded_run_says_why_it_cannot_be_plotted() -> None:
    pytest.importorskip("matplotlib")
    s = ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"duration": 0.05, "simulation.record_rate": 0.0})
    r = ftsmc.simulate(s, "pid")
    with pytest.raises(ValueError, match="record_rate") as e:
        r.plot()
    _nonempty(e.value)


def test_num_envs_is_priced_with_a_message() -> None:
    gym = pytest.importorskip("gymnasium")
    importlib.import_module("ftsmc.gym")  # registers the environments

    for n in [10**9, 10**7]:
        with pytest.raises(ValueError, match="num_envs") as e:
            gym.make_vec("ftsmc/Hover-v0", num_envs=n, vectorization_mode="vector_entry_point")
        _nonempty(e.value)


def test_a_non_toml_file_is_never_echoed(tmp_path: Any) -> None:
    secret = tmp_path / "passwd"
    secret.write_text("root:x:0:0:root:/root:/bin/bash\n")
    with pytest.raises(ValueError) as e:
        ftsmc.Scenario.from_file(str(secret))
    assert "root" not in _nonempty(e.value).replace(str(tmp_path), "")
    gym = pytest.importorskip("gymnasium")
    importlib.import_module("ftsmc.gym")

    with pytest.raises(ValueError) as e:
        gym.make("ftsmc/Hover-v0", scenario=str(secret))
    assert "root" not in _nonempty(e.value).replace(str(tmp_path), "")
