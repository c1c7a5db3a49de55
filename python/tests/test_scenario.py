"""Loading and overrides: every path validates as a file would, and a bad
key or value raises ValueError naming it."""

from __future__ import annotations

from pathlib import Path

import pytest

import ftsmc


def test_builtin_file_and_text_give_the_same_scenario(tmp_path: Path) -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-2")
    path = tmp_path / "s.toml"
    path.write_text(s.to_toml())
    assert ftsmc.Scenario.from_file(path) == s
    assert ftsmc.Scenario.from_file(str(path)) == s
    assert ftsmc.Scenario.from_toml(s.to_toml()) == s
    assert ftsmc.Scenario.builtin("paper-scenario-2.toml") == s
    assert s.name == "paper-scenario-2" and s.duration == 50.0 and s.seed == 2
    assert s.controllers == ["ranftsmc", "tsm-sta", "ftaftsmc"]
    assert s.control_period == pytest.approx(1e-3)


def test_extends_resolves_relative_to_the_file(tmp_path: Path) -> None:
    (tmp_path / "mine.toml").write_text('extends = "paper-scenario-1"\nname = "mine"\n[ftaftsmc.z]\nlambda2 = 0.8\n')
    mine = ftsmc.Scenario.from_file(tmp_path / "mine.toml")
    base = ftsmc.Scenario.builtin("paper-scenario-1")
    assert mine == base.with_overrides({"name": "mine", "ftaftsmc.z.lambda2": 0.8})


def test_overrides_return_a_new_validated_scenario() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-2")
    t = s.with_overrides({"payload.mass": 0.5, "ftaftsmc.z.lambda2": 0.8, "seed": 9})
    assert t != s and t.seed == 9 and s.seed == 2
    assert 'lambda2 = 0.8' in t.to_toml()
    assert "mass = 0.5" in t.to_toml().split("[payload]")[1]
    # an int where a float is expected is fine; a whole table is a dict
    u = s.with_overrides({"duration": 45, "reference.z": {"terms": [{"type": "constant", "value": 2.0}]}})
    assert u.duration == 45.0
    run = ftsmc.simulate(u, "ftaftsmc")
    assert run.exit.status == "completed"
    assert abs(run.columns["z"][-1] - 2.0) < 0.05


@pytest.mark.parametrize(
    "overrides, named",
    [
        ({"ftaftsmc.z.lambda9": 0.8}, "lambda9"),  # unknown key
        ({"ftaftsmc.z.lambda2": -0.8}, "`ftaftsmc.z.lambda2` = -0.8"),  # out of range
        ({"ftaftsmc.z.lambda2": "fast"}, "ftaftsmc.z.lambda2"),  # wrong type
        ({"simulation.control_rate": 0.0}, "simulation.control_rate"),
        ({"duration.x": 1.0}, "`duration` is a float, not a table"),
        ({"payload..mass": 1.0}, "payload..mass"),
        ({"ftaftsmc.z.lambda2": object()}, "ftaftsmc.z.lambda2"),
    ],
)
def test_a_bad_override_raises_value_error_naming_the_key(overrides: dict[str, object], named: str) -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-2")
    with pytest.raises(ValueError) as err:
        s.with_overrides(overrides)
    assert named in str(err.value), str(err.value)


def test_a_missing_field_of_a_new_section_is_named() -> None:
    with pytest.raises(ValueError, match="missing field `start` in `payload`"):
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"payload.mass": 0.5})


def test_load_errors_carry_the_cli_message(tmp_path: Path) -> None:
    with pytest.raises(ValueError, match="no built-in scenario `nope`"):
        ftsmc.Scenario.builtin("nope")
    with pytest.raises(ValueError, match="cannot read scenario file .*missing.toml: No such file"):
        ftsmc.Scenario.from_file(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "bad"\nduration = 1.0\n[plant]\nmass = -1.0\n')
    with pytest.raises(ValueError, match=r"bad.toml: `plant.mass` = -1"):
        ftsmc.Scenario.from_file(bad)
    with pytest.raises(ValueError, match="unknown controller `nope` \\(known: ftaftsmc"):
        ftsmc.simulate(ftsmc.Scenario.builtin("paper-scenario-1"), "nope")
    with pytest.raises(ValueError, match="runs must be at least 1"):
        ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-1"), 0)


def test_cost_limits_apply_as_in_the_cli() -> None:
    with pytest.raises(ValueError, match="exceeds the limit max_steps = 10"):
        ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"limits.max_steps": 10.0})
    with pytest.raises(ValueError, match="max_flights"):
        ftsmc.montecarlo(ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"limits.max_flights": 5.0}), 2)


def test_unit_slip_warnings_are_python_warnings() -> None:
    with pytest.warns(UserWarning, match="`simulation.metrics_window` = \\[10, 40\\]: starts after the end of the run"):
        ftsmc.Scenario.builtin("paper-scenario-2").with_overrides({"duration": 5.0})


def test_registry_listing() -> None:
    assert "ftaftsmc" in ftsmc.CONTROLLERS and ftsmc.label("ftaftsmc") == "FTAFTSMC"


def _section(text: str, key: str) -> str:
    """The lines of table `[key]` in a scenario's TOML text."""
    lines = text.splitlines()
    start = lines.index(f"[{key}]")
    end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("[")), len(lines))
    return "\n".join(lines[start:end])


def test_vehicle_derived_gains_follow_a_plant_override_unless_set() -> None:
    base = ftsmc.Scenario.builtin("paper-scenario-1")
    heavy = base.with_overrides({"plant.mass": 1.5})
    # pid's hover thrust and se3's position gain are derived from the mass.
    assert "hover_thrust = 14.715" in _section(heavy.to_toml(), "pid")
    assert _section(heavy.to_toml(), "se3") != _section(base.to_toml(), "se3")
    # The sliding-mode gains are the paper's whatever the vehicle.
    assert _section(heavy.to_toml(), "ftaftsmc.x") == _section(base.to_toml(), "ftaftsmc.x")
    # A key the user sets is kept; the rest of the section still follows the plant.
    tuned = base.with_overrides({"pid.position_p": [2.0, 2.0, 1.5]}).with_overrides({"plant.mass": 1.5})
    pid = _section(tuned.to_toml(), "pid")
    assert "position_p = [2.0, 2.0, 1.5]" in pid
    assert "hover_thrust = 7.2594" in pid  # a changed section is kept whole


def test_one_list_of_built_in_scenarios() -> None:
    names = ftsmc.Scenario.builtin_names()
    assert "paper-scenario-1" in names and "realistic-moderate-2" in names
    for name in names:
        assert ftsmc.Scenario.builtin(name).name
    with pytest.raises(ValueError) as err:
        ftsmc.Scenario.builtin("nope")
    for name in names:
        assert name in str(err.value), str(err.value)


def test_true_vehicle_overrides_use_the_vehicle_section() -> None:
    base = ftsmc.Scenario.builtin("paper-scenario-1").with_overrides({"duration": 2.0})
    new = base.with_overrides({"vehicle.mass": 0.85, "vehicle.inertia": [4.2e-3, 4.2e-3, 8.1e-3]})
    vehicle = _section(new.to_toml(), "vehicle")
    assert "mass = 0.85" in vehicle and "inertia = [0.0042, 0.0042, 0.0081]" in vehicle
    assert "mass = 0.74" in _section(new.to_toml(), "plant"), "the controllers' model stays [plant]"
    # The old spelling still loads, warns naming the new key, and is the same scenario.
    with pytest.warns(UserWarning, match=r"actual_plant\.mass.*\[vehicle\] mass"):
        old = base.with_overrides({"actual_plant.mass": 0.85, "actual_plant.inertia": [4.2e-3, 4.2e-3, 8.1e-3]})
    assert old.to_toml() == new.to_toml()
    flown_new = ftsmc.simulate(new, "ftaftsmc").columns
    flown_old = ftsmc.simulate(old, "ftaftsmc").columns
    assert all((flown_new[c] == flown_old[c]).all() for c in flown_new)
    # The true vehicle is what flies: the recorded true mass is the override's.
    assert flown_new["mass_true"][0] == 0.85
    # A key only the rigid body flies is refused on the paper model, naming the model.
    with pytest.raises(ValueError, match=r"vehicle\.parasitic_drag.*model = \"paper\""):
        base.with_overrides({"vehicle.parasitic_drag": [0.01, 0.01, 0.02]})
    rigid = base.with_overrides({"vehicle.model": "rigid-body", "vehicle.parasitic_drag": [0.01, 0.01, 0.02]})
    assert "parasitic_drag = [0.01, 0.01, 0.02]" in _section(rigid.to_toml(), "vehicle")
    # Mixing the spellings is refused, naming both keys.
    with pytest.raises(ValueError, match=r"vehicle\.mass.*actual_plant\.gravity"):
        new.with_overrides({"actual_plant.gravity": 9.8})
