"""The paper's published sliding-mode gains on a vehicle of another size:
Python's montecarlo and compare refuse them, as the CLI does, when the
scenario's nominal flight fails with them, and fly them when asked."""

from __future__ import annotations

import pytest

import ftsmc


def x500() -> ftsmc.Scenario:
    return ftsmc.Scenario.builtin("realistic-calm-1").with_overrides({"vehicle.preset": "px4-x500"})


def test_montecarlo_refuses_unfit_published_gains_naming_the_remedies() -> None:
    with pytest.raises(ValueError) as e:
        ftsmc.montecarlo(x500(), runs=1, controllers=["ranftsmc"])
    text = str(e.value)
    assert "px4-x500" in text and "ftsmc tune" in text and "simulation.unfit_gains=fly" in text


def test_unfit_gains_fly_lets_them_through_and_pid_is_never_checked() -> None:
    fly = x500().with_overrides({"simulation.unfit_gains": "fly", "duration": 1.0})
    runs = ftsmc.montecarlo(fly, runs=1, controllers=["ranftsmc"])
    assert len(runs) == 1
    pid = ftsmc.montecarlo(x500().with_overrides({"duration": 1.0}), runs=1, controllers=["pid"])
    assert len(pid) == 1
