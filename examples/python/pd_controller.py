"""A user-written PD controller flown in ftsmc's plant, beside FTAFTSMC.

    python examples/python/pd_controller.py

`ftsmc.simulate(scenario, controller=obj)` calls `obj.update(state,
reference, dt)` once per control period (1 kHz here) and holds the
returned command; see ftsmc.State / Reference / Command for fields and units.
"""

from __future__ import annotations

import math
import time
from typing import Sequence

import ftsmc


class PD:
    """Position PD → desired acceleration → thrust and small-angle attitude
    demand → attitude PD torques, on the scenario's nominal model."""

    name = "pd"

    def __init__(self, mass: float, gravity: float, inertia: Sequence[float]) -> None:
        self.mass, self.gravity, self.inertia = mass, gravity, list(inertia)
        self.kp, self.kd = 4.0, 4.0  # position, 1/s² and 1/s
        self.kp_att, self.kd_att = 100.0, 20.0  # attitude, 1/s² and 1/s

    def update(self, state: ftsmc.State, reference: ftsmc.Reference, dt: float) -> ftsmc.Command:
        a = [
            reference.acceleration[i]
            - self.kp * (state.position[i] - reference.position[i])
            - self.kd * (state.velocity[i] - reference.velocity[i])
            for i in range(3)
        ]
        phi, theta, psi = state.attitude
        thrust = self.mass * (a[2] + self.gravity) / (math.cos(phi) * math.cos(theta))
        phi_d = (a[0] * math.sin(psi) - a[1] * math.cos(psi)) / self.gravity
        theta_d = (a[0] * math.cos(psi) + a[1] * math.sin(psi)) / self.gravity
        demand = (phi_d, theta_d, reference.yaw)
        torque = tuple(
            self.inertia[i] * (-self.kp_att * (state.attitude[i] - demand[i]) - self.kd_att * state.angular_rate[i])
            for i in range(3)
        )
        return ftsmc.Command(thrust, (torque[0], torque[1], torque[2]))


def main() -> None:
    scenario = ftsmc.Scenario.builtin("paper-scenario-1")
    pd = PD(mass=0.74, gravity=9.81, inertia=(3.827e-3, 3.827e-3, 7.6566e-3))
    started = time.perf_counter()
    mine = ftsmc.simulate(scenario, pd)
    elapsed = time.perf_counter() - started
    reference = ftsmc.simulate(scenario, "ftaftsmc")
    print(f"PD flown in {elapsed:.2f} s for {mine.steps} steps ({1e6 * elapsed / mine.steps:.1f} µs per step)")
    for run in (mine, reference):
        ise = run.metrics["ise"]
        print(f"{run.controller:>10}: {run.exit.text}; ISE x {ise['x']:.4f}, y {ise['y']:.4f}, z {ise['z']:.4f}")


if __name__ == "__main__":
    main()
