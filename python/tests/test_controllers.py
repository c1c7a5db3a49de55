"""Controllers across the boundary: a Python controller flown by ftsmc, and
ftsmc's controller stepped from Python giving the same commands as inside
ftsmc's own loop."""

from __future__ import annotations

import dataclasses
import math
import re
from typing import List

import numpy as np
import pytest

import ftsmc


class Pd:
    """A PD hover controller on the paper's model (small-angle inversion)."""

    name = "pd"

    def __init__(self, mass: float, gravity: float, inertia: List[float]) -> None:
        self.m, self.g, self.inertia = mass, gravity, inertia
        self.calls = 0

    def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
        self.calls += 1
        e = np.subtract(state.position, reference.position)
        de = np.subtract(state.velocity, reference.velocity)
        a = np.asarray(reference.acceleration) - 4.0 * e - 4.0 * de  # desired acceleration
        thrust = self.m * (a[2] + self.g) / (np.cos(state.attitude[0]) * np.cos(state.attitude[1]))
        psi = state.attitude[2]
        phi_d = (a[0] * np.sin(psi) - a[1] * np.cos(psi)) / self.g
        theta_d = (a[0] * np.cos(psi) + a[1] * np.sin(psi)) / self.g
        att_d = np.array([phi_d, theta_d, reference.yaw])
        torque = np.asarray(self.inertia) * (-100.0 * (np.asarray(state.attitude) - att_d) - 20.0 * np.asarray(state.angular_rate))
        return ftsmc.Command(float(thrust), (float(torque[0]), float(torque[1]), float(torque[2])))


def hover() -> ftsmc.Scenario:
    return ftsmc.Scenario.builtin("paper-scenario-1").with_overrides(
        {
            "duration": 6.0,
            "initial_state.position": [0.3, -0.2, 0.5],
            "initial_state.attitude": [0.0, 0.0, 0.0],
            "reference.x": {"terms": [{"type": "constant", "value": 0.0}]},
            "reference.y": {"terms": [{"type": "constant", "value": 0.0}]},
            "reference.z": {"terms": [{"type": "constant", "value": 1.0}]},
            "reference.psi": {"terms": [{"type": "constant", "value": 0.0}]},
        }
    )


def test_a_python_controller_flies_the_hover() -> None:
    s = hover()
    pd = Pd(0.74, 9.81, [3.827e-3, 3.827e-3, 7.6566e-3])
    run = ftsmc.simulate(s, pd)
    assert run.controller == "pd"
    assert run.exit.status == "completed"
    assert pd.calls == run.steps == 6000
    final = np.array([run.columns[k][-1] for k in ("x", "y", "z")])
    np.testing.assert_allclose(final, [0.0, 0.0, 1.0], atol=0.02)
    assert 0.0 < run.metrics["ise"]["z"] < 0.5 and run.metrics["completed"] is True


def test_a_python_exception_ends_the_flight_and_is_raised() -> None:
    class Broken:
        def __init__(self) -> None:
            self.calls = 0

        def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
            self.calls += 1
            if self.calls == 5:
                raise RuntimeError("boom at 5")
            return ftsmc.Command(7.26, (0.0, 0.0, 0.0))

    broken = Broken()
    with pytest.raises(RuntimeError, match="boom at 5"):
        ftsmc.simulate(hover(), broken)
    assert broken.calls == 5


def test_a_malformed_command_is_a_value_error() -> None:
    class Bad:
        def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> object:
            return (1.0, 2.0)

    with pytest.raises(ValueError, match="thrust"):
        ftsmc.simulate(hover(), Bad())  # type: ignore[arg-type]


class Replay:
    """Flies ftsmc's controller through ftsmc.Controller.update, recording
    what it returned and its attitude reference."""

    def __init__(self, name: str, scenario: ftsmc.Scenario) -> None:
        self.inner = ftsmc.Controller(name, scenario)
        self.commands: List[ftsmc.Command] = []
        self.attitude_reference: List[ftsmc.Vec3] = []

    def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
        command = self.inner.update(state, reference, dt)
        self.commands.append(command)
        self.attitude_reference.append(self.inner.telemetry.attitude_reference)
        return command


@pytest.mark.parametrize("name", ["ftaftsmc", "ranftsmc", "tsm-sta"])
def test_controller_update_matches_the_rust_controller_along_a_recorded_flight(name: str) -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-2").with_overrides({"duration": 12.0})
    recorded = ftsmc.simulate(s, name)
    replay = Replay(name, s)
    through_python = ftsmc.simulate(s, replay)
    every = round(1.0 / s.control_period / 100.0)  # record_rate 100 Hz
    cols = recorded.columns
    commands = np.array([[c.thrust, *c.torque] for c in replay.commands])[::every]
    expected = np.column_stack([cols[k] for k in ("thrust_cmd", "roll_torque_cmd", "pitch_torque_cmd", "yaw_torque_cmd")])
    np.testing.assert_array_equal(commands, expected)
    att = np.array(replay.attitude_reference)[::every]
    np.testing.assert_array_equal(att, np.column_stack([cols["phi_ref"], cols["theta_ref"], cols["psi_ref"]]))
    for k in ("x", "y", "z", "phi", "theta", "psi", "vx", "vy", "vz", "phi_rate", "theta_rate", "psi_rate"):
        np.testing.assert_array_equal(through_python.columns[k], cols[k], err_msg=k)


def test_reset_restores_the_initial_states() -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-1")
    c = ftsmc.Controller("ftaftsmc", s)
    state = ftsmc.State(position=(0.5, -0.2, 0.1), attitude=(0.05, 0.0, 0.1))
    ref = ftsmc.Reference(position=(0.0, 0.0, 1.0))
    first = c.update(state, ref, 1e-3)
    for _ in range(50):
        c.update(state, ref, 1e-3)
    assert c.update(state, ref, 1e-3) != first
    c.reset()
    assert c.update(state, ref, 1e-3) == first
    with pytest.raises(ValueError, match="`dt` = 0"):
        c.update(state, ref, 0.0)
    with pytest.raises(ValueError, match="unknown controller"):
        ftsmc.Controller("nope", s)


FIVE = ["ftaftsmc", "ranftsmc", "tsm-sta", "pid", "se3"]


@pytest.mark.parametrize("name", FIVE)
@pytest.mark.parametrize(
    "field, bad",
    [
        ("state.position[1]", float("nan")),
        ("state.attitude[0]", float("inf")),
        ("state.velocity[2]", float("-inf")),
        ("state.angular_rate[1]", float("nan")),
        ("reference.position[0]", float("nan")),
        ("reference.velocity[1]", float("inf")),
        ("reference.acceleration[2]", float("nan")),
        ("reference.yaw", float("nan")),
        ("reference.yaw_rate", float("inf")),
        ("reference.yaw_acceleration", float("-inf")),
    ],
)
def test_a_non_finite_input_raises_naming_its_field(name: str, field: str, bad: float) -> None:
    s = ftsmc.Scenario.builtin("paper-scenario-1")
    state = ftsmc.State((0.1, -0.2, 0.5), (0.01, 0.02, 0.03), (0.0, 0.1, 0.0), (0.0, 0.0, 0.1))
    reference = ftsmc.Reference((0.0, 0.0, 1.0), (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), 0.0, 0.0, 0.0)
    where, _, rest = field.partition(".")
    attr, _, index = rest.partition("[")
    target = state if where == "state" else reference
    if index:
        values = list(getattr(target, attr))
        values[int(index.rstrip("]"))] = bad
        bad_target = dataclasses.replace(target, **{attr: tuple(values)})
    else:
        bad_target = dataclasses.replace(target, **{attr: bad})
    bad_state, bad_reference = (bad_target, reference) if where == "state" else (state, bad_target)
    c = ftsmc.Controller(name, s)
    shown = "nan" if math.isnan(bad) else repr(bad)
    with pytest.raises(ValueError, match=re.escape(f"Controller.update: {field} is {shown};")):
        c.update(bad_state, bad_reference, 0.01)
    flat_state = (*bad_state.position, *bad_state.attitude, *bad_state.velocity, *bad_state.angular_rate)
    flat_reference = (
        *bad_reference.position,
        *bad_reference.velocity,
        *bad_reference.acceleration,
        bad_reference.yaw,
        bad_reference.yaw_rate,
        bad_reference.yaw_acceleration,
    )
    with pytest.raises(ValueError, match=re.escape(field)):
        c.update_arrays(flat_state, flat_reference, 0.01)
    # The refused calls left the controller as built: its next command is a fresh one's.
    fresh = ftsmc.Controller(name, s)
    assert c.update(state, reference, 0.01) == fresh.update(state, reference, 0.01)
