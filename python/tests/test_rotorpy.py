"""The RotorPy adapter: frame conversions against RotorPy's own kinematics,
and flights in RotorPy's simulator that track a hover (in wind) and a step."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import ftsmc
import ftsmc.rotorpy as fr

pytest.importorskip("rotorpy", reason="pip install rotorpy (.ci/run installs it)")
from rotorpy.vehicles.hummingbird_params import quad_params  # noqa: E402
from rotorpy.vehicles.multirotor import quat_dot  # noqa: E402
from scipy.spatial.transform import Rotation  # noqa: E402

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "python" / "rotorpy_ftaftsmc.py"


def _example():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("rotorpy_example", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["rotorpy_example"] = module
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("angles", [(0.3, -0.2, 0.7), (-1.0, 0.5, -2.9), (0.0, 0.0, 3.1)])
def test_quaternion_and_euler_conversions_match_scipy_and_rotorpy(angles: tuple) -> None:
    q = fr.quaternion_zyx(*angles)
    np.testing.assert_allclose(Rotation.from_euler("ZYX", angles[::-1]).as_quat(), q, atol=1e-12)
    np.testing.assert_allclose(fr.euler_zyx(q), angles, atol=1e-12)
    # Euler-angle rates: finite difference of RotorPy's own quaternion kinematics.
    w, h = np.array([0.4, -0.7, 1.1]), 1e-7
    q2 = q + h * quat_dot(q, w)
    rates = (np.array(fr.euler_zyx(q2 / np.linalg.norm(q2))) - np.array(angles)) / h
    np.testing.assert_allclose(fr.euler_rates(angles[0], angles[1], w), rates, rtol=1e-5, atol=1e-5)


def test_the_nominal_model_is_the_rotorpy_vehicle() -> None:
    s = fr.scenario_for(quad_params)
    plant = fr.plant_from_rotorpy(quad_params)
    assert plant["mass"] == 0.5 and plant["inertia"] == [3.65e-3, 3.68e-3, 7.03e-3]
    assert plant["lift_coefficient"] == 5.57e-6 and plant["yaw_drag_coefficient"] == 1.36e-7
    assert plant["arm_length"] == pytest.approx(0.17) and plant["rotor_inertia"] == 0.0
    hover = np.sqrt(0.5 * 9.81 / (4 * 5.57e-6))
    np.testing.assert_allclose(plant["drag_translational"], [4 * 1.19e-4 * hover, 4 * 1.19e-4 * hover, 4 * 2.32e-4 * hover])
    expected = {"name": "rotorpy-500g-paper-scenario-1", **{f"plant.{k}": v for k, v in plant.items()}}
    assert s == ftsmc.Scenario.builtin("paper-scenario-1").with_overrides(expected)
    # Named after the vehicle, not after the paper's scenario it extends.
    assert s.name == "rotorpy-500g-paper-scenario-1"
    assert fr.scenario_for(quad_params, vehicle="hummingbird").name == "hummingbird-paper-scenario-1"


def test_control_dict_feeds_every_rotorpy_abstraction_we_claim() -> None:
    c = fr.Controller("ftaftsmc", quad_params)
    state = {"x": np.zeros(3), "v": np.zeros(3), "q": np.array([0, 0, 0, 1.0]), "w": np.zeros(3)}
    flat = {"x": np.zeros(3), "x_dot": np.zeros(3), "x_ddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0}
    u = c.update(0.0, state, flat)
    assert u["cmd_thrust"] == pytest.approx(0.5 * 9.81)  # hover: weight
    np.testing.assert_allclose(u["cmd_moment"], 0.0, atol=1e-12)
    np.testing.assert_allclose(u["cmd_motor_speeds"], np.sqrt(0.5 * 9.81 / 4 / quad_params["k_eta"]), rtol=1e-9)
    assert set(u) >= {"cmd_thrust", "cmd_moment", "cmd_motor_speeds", "cmd_motor_thrusts", "cmd_q", "cmd_w", "cmd_v"}


@pytest.mark.parametrize(
    "controller",
    [
        "tsm-sta",
        "ranftsmc",
        "pid",
        "se3",
        pytest.param(
            "ftaftsmc",
            marks=pytest.mark.xfail(
                strict=True,
                reason="the paper's FTAFTSMC gains lose control of RotorPy's Hummingbird (docs/python.md)",
            ),
        ),
    ],
)
def test_a_rotorpy_flight_tracks_a_hover_in_wind_and_a_step(controller: str) -> None:
    example = _example()
    target, t_step = np.array([0.5, 0.0, 0.3]), 3.0
    result = example.fly(controller, 6.0, 500.0, target, t_step)
    numbers = example.tracking(result, target, t_step)
    assert numbers["flown_s"] == pytest.approx(6.0, abs=0.01)
    assert numbers["hover_max_error_m"] < 0.15, numbers
    # PX4's default position loop (MPC_XY_P 0.95, ω_n 1.3 rad/s) behind its
    # shipped MC_ROLL_P = 4.0 is the slowest of the four: 13.2 cm 3 s after
    # the step (10.8 cm with the older 6.5); the others stay under 8 cm.
    assert numbers["step_max_error_m"] < (0.15 if controller == "pid" else 0.12), numbers


def test_a_rotorpy_controller_flies_in_ftsmcs_plant() -> None:
    """The bridge the other way: RotorPy's SE(3) controller, built for the
    Hummingbird, flies paper scenario 1's steps in ftsmc's plant of the same
    vehicle and reaches the 1 m steps."""
    from rotorpy.controllers.quadrotor_control import SE3Control

    scenario = fr.scenario_for(quad_params, overrides={"duration": 8.0})
    run = ftsmc.simulate(scenario, fr.from_rotorpy(SE3Control(quad_params)))
    assert run.exit.status == "completed", run.exit.text
    c = run.columns
    for axis in ("x", "y", "z"):
        assert abs(c[axis][-1] - c[f"{axis}_ref"][-1]) < 0.05, (axis, c[axis][-1])
    # body rates ↔ Euler-angle rates round trip
    rates = fr.euler_rates(0.3, -0.2, fr.body_rates(0.3, -0.2, (0.1, -0.4, 0.9)))
    np.testing.assert_allclose(rates, (0.1, -0.4, 0.9), atol=1e-12)
