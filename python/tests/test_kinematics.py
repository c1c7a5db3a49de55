"""ftsmc.rotorpy's state conversions are ftsmc-core's kinematics (one
implementation for the controllers, the simulator and Python): Euler ↔
quaternion ↔ Euler and Euler rates ↔ body rates round trips, the
quaternion's rotation against the Z-Y-X matrix, and clear errors for
arrays of the wrong length."""

import math

import numpy as np
import pytest

import ftsmc
from ftsmc import _ftsmc
from ftsmc import rotorpy as conv


def rotation_zyx(phi: float, theta: float, psi: float) -> np.ndarray:
    cx, sx, cy, sy, cz, sz = (math.cos(phi), math.sin(phi), math.cos(theta), math.sin(theta), math.cos(psi), math.sin(psi))
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def rotation_of_xyzw(q: np.ndarray) -> np.ndarray:
    x, y, z, w = q
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def test_round_trips_and_rotation() -> None:
    rng = np.random.default_rng(5)
    for _ in range(200):
        phi, psi = rng.uniform(-3.1, 3.1, 2)
        theta = rng.uniform(-1.5, 1.5)
        q = conv.quaternion_zyx(phi, theta, psi)
        assert abs(np.linalg.norm(q) - 1.0) < 1e-14
        np.testing.assert_allclose(rotation_of_xyzw(q), rotation_zyx(phi, theta, psi), atol=1e-14)
        np.testing.assert_allclose(conv.euler_zyx(q), (phi, theta, psi), atol=1e-11)
        np.testing.assert_allclose(conv.euler_zyx(-3.0 * q), (phi, theta, psi), atol=1e-11)  # scale, sign
        rates = rng.uniform(-5, 5, 3)
        body = conv.body_rates(phi, theta, rates)
        np.testing.assert_allclose(conv.euler_rates(phi, theta, body), rates, atol=1e-9)


def test_wrong_lengths_are_refused_naming_the_argument() -> None:
    with pytest.raises(ValueError, match="body_rates: expected 3 numbers, got 2"):
        _ftsmc.kinematics_euler_rates([0.0, 0.0, 0.0], [1.0, 2.0])
    with pytest.raises(ValueError, match="q: expected 4 numbers, got 3"):
        _ftsmc.kinematics_euler_from_quaternion([1.0, 0.0, 0.0])


def test_pid_and_se3_report_no_sliding_variables() -> None:
    scenario = ftsmc.Scenario.builtin("paper-scenario-1")
    state, reference = ftsmc.State(), ftsmc.Reference(position=(0.1, 0.0, 1.0))
    for name, sliding in [("pid", False), ("se3", False), ("ftaftsmc", True)]:
        c = ftsmc.Controller(name, scenario)
        c.update(state, reference, 1e-3)
        t = c.telemetry
        assert (t.sliding is not None) == sliding and (t.alpha_hat is not None) == sliding, name
