"""An empty controller list or name is refused by every function that takes
controllers, with the library's message (ftsmc_sim::registry::ControllerList,
the CLI's `-c` check) naming the argument and the value."""

from __future__ import annotations

import pytest

import ftsmc

EMPTY_LIST = "no controller named \\(an empty list\\)"


@pytest.fixture(scope="module")
def scenario() -> ftsmc.Scenario:
    return ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"duration": 0.5})


def test_montecarlo_refuses_an_empty_list_and_an_empty_name(scenario: ftsmc.Scenario) -> None:
    with pytest.raises(ValueError, match="^controllers: " + EMPTY_LIST):
        ftsmc.montecarlo(scenario, 2, controllers=[])
    with pytest.raises(ValueError, match="^controllers `pid,`: no controller named in entry 2 of 2"):
        ftsmc.montecarlo(scenario, 2, controllers=["pid", ""])
    with pytest.raises(ValueError, match="^controllers ` `: no controller named in entry 1 of 1"):
        ftsmc.montecarlo(scenario, 2, controllers=" ")


def test_compare_refuses_an_empty_list_and_an_empty_name(scenario: ftsmc.Scenario) -> None:
    with pytest.raises(ValueError, match="^contestants: " + EMPTY_LIST):
        ftsmc.compare(scenario, [], runs=2)
    with pytest.raises(ValueError, match="^contestants `pid,`: no controller named in entry 2 of 2"):
        ftsmc.compare(scenario, ["pid", ""], runs=2)


def test_tune_falsify_and_simulate_refuse_an_empty_name(scenario: ftsmc.Scenario) -> None:
    empty = "^controller ``: no controller named in entry 1 of 1"
    with pytest.raises(ValueError, match=empty):
        ftsmc.tune(scenario, "", budget=10)
    with pytest.raises(ValueError, match=empty):
        ftsmc.falsify(scenario, "", budget=2)
    with pytest.raises(ValueError, match=empty):
        ftsmc.simulate(scenario, "")


def test_an_unknown_name_still_lists_the_known_ones(scenario: ftsmc.Scenario) -> None:
    with pytest.raises(ValueError, match="unknown controller `nope` \\(known: ftaftsmc"):
        ftsmc.montecarlo(scenario, 2, controllers=["nope"])
