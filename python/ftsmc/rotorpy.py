"""ftsmc's controllers in RotorPy's simulator.

RotorPy (``pip install rotorpy``) calls a controller as
``update(t, state, flat_output) -> control dict``; :class:`Controller` does
that with any ftsmc controller, by name::

    from rotorpy.vehicles.hummingbird_params import quad_params
    from rotorpy.vehicles.multirotor import Multirotor
    import ftsmc.rotorpy

    controller = ftsmc.rotorpy.Controller("ftaftsmc", quad_params)
    vehicle = Multirotor(quad_params, control_abstraction="cmd_ctbm")

Frames (checked against RotorPy's ``Multirotor``): RotorPy's world frame is
z up (gravity ``[0, 0, -m g]``), its body frame is x forward, y left, z up
(thrust along body +z), ``state["q"]`` is the body-to-world quaternion
``[x, y, z, w]`` and ``state["w"]`` the body rates (rad/s). ftsmc uses the
same world and body axes with Z-Y-X Euler angles and their rates, so the
adapter converts the quaternion to ``(φ, θ, ψ)`` (yaw unwrapped to stay
continuous) and the body rates to Euler-angle rates. ftsmc's command
(total thrust N, body torques N·m) is RotorPy's ``cmd_ctbm`` abstraction
(``cmd_thrust``, ``cmd_moment``); the dict also carries the motor speeds of
the same command through RotorPy's own allocation (``cmd_motor_speeds``,
for ``control_abstraction="cmd_motor_speeds"``) and the attitude reference
as ``cmd_q``.

The controller's nominal model is the RotorPy vehicle (see
:func:`plant_from_rotorpy`); the gains are the base scenario's (default
``paper-scenario-1``, the paper's FTAFTSMC gains).
"""

from __future__ import annotations

import math
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import Scenario, _ftsmc

__all__ = [
    "Controller",
    "FromRotorPy",
    "body_rates",
    "euler_rates",
    "euler_zyx",
    "from_rotorpy",
    "plant_from_rotorpy",
    "quaternion_zyx",
    "scenario_for",
]


def euler_zyx(q: Sequence[float]) -> Tuple[float, float, float]:
    """Z-Y-X Euler angles ``(φ, θ, ψ)`` (rad) of the body-to-world
    quaternion ``q = [x, y, z, w]`` (RotorPy's and scipy's order), normalised
    first; ftsmc-core's ``kinematics::euler_from_quaternion``."""
    x, y, z, w = (float(v) for v in q)
    n = math.sqrt(x * x + y * y + z * z + w * w)
    phi, theta, psi = _ftsmc.kinematics_euler_from_quaternion([w / n, x / n, y / n, z / n])
    return float(phi), float(theta), float(psi)


def quaternion_zyx(phi: float, theta: float, psi: float) -> np.ndarray:
    """The body-to-world quaternion ``[x, y, z, w]`` of Z-Y-X Euler angles
    (rad); ftsmc-core's ``kinematics::quaternion_from_euler``."""
    w, x, y, z = _ftsmc.kinematics_quaternion_from_euler([phi, theta, psi])
    return np.array([x, y, z, w])


def euler_rates(phi: float, theta: float, body_rates: Sequence[float]) -> Tuple[float, float, float]:
    """Euler-angle rates ``(φ̇, θ̇, ψ̇)`` (rad/s) from body rates ``(p, q, r)``
    (rad/s) at roll ``phi`` and pitch ``theta`` (rad): ``W(φ, θ) ω``
    (ftsmc-core's ``kinematics::euler_rates_from_body_rates``; ``cos θ``
    clamped to ±1e-6 at gimbal lock)."""
    a, b, c = _ftsmc.kinematics_euler_rates([phi, theta, 0.0], [float(v) for v in body_rates])
    return float(a), float(b), float(c)


def plant_from_rotorpy(quad_params: Mapping[str, Any], aero: bool = True) -> Dict[str, Any]:
    """ftsmc's ``[plant]`` (the controllers' nominal model, paper Eq. 1) of
    a RotorPy vehicle:

    - ``mass``, ``inertia = [Ixx, Iyy, Izz]`` (products of inertia are
      dropped: the model is diagonal), ``gravity = 9.81`` (RotorPy's);
    - ``lift_coefficient = k_eta``, ``yaw_drag_coefficient = k_m``,
      ``arm_length`` = distance of rotor 1 from the centre of mass;
    - ``rotor_inertia = 0`` and ``drag_rotational = 0``: RotorPy models no
      rotor gyroscopic torque and no rotational drag;
    - ``drag_translational``: RotorPy's rotor drag (H-force) is linear in
      the airspeed with slope ``k_d Ω`` per rotor (``k_z Ω`` along z), which
      at the hover speed ``Ω_h = sqrt(m g / (4 k_eta))`` is the paper's
      linear drag ``4 k_d Ω_h`` (x, y) and ``4 k_z Ω_h`` (z), N·s/m; zero
      with ``aero=False``. The quadratic frame drag (``c_D``) has no
      counterpart in Eq. 1 and is left to the robust terms.
    """
    mass = float(quad_params["mass"])
    k_eta = float(quad_params["k_eta"])
    hover = math.sqrt(mass * 9.81 / (4.0 * k_eta))
    k_d = float(quad_params.get("k_d", 0.0)) if aero else 0.0
    k_z = float(quad_params.get("k_z", 0.0)) if aero else 0.0
    first_rotor = np.asarray(next(iter(quad_params["rotor_pos"].values())), dtype=float)
    return {
        "mass": mass,
        "gravity": 9.81,
        "inertia": [float(quad_params["Ixx"]), float(quad_params["Iyy"]), float(quad_params["Izz"])],
        "rotor_inertia": 0.0,
        "drag_translational": [4.0 * k_d * hover, 4.0 * k_d * hover, 4.0 * k_z * hover],
        "drag_rotational": [0.0, 0.0, 0.0],
        "lift_coefficient": k_eta,
        "yaw_drag_coefficient": float(quad_params["k_m"]),
        "arm_length": float(np.linalg.norm(first_rotor[:2])),
    }


def scenario_for(
    quad_params: Mapping[str, Any],
    base: Optional[Scenario] = None,
    overrides: Optional[Mapping[str, Any]] = None,
    aero: bool = True,
    vehicle: Optional[str] = None,
) -> Scenario:
    """``base`` (default ``paper-scenario-1``: the paper's gains) with its
    ``[plant]`` replaced by :func:`plant_from_rotorpy` and then ``overrides``
    applied (dotted keys, e.g. ``{"ftaftsmc.z.lambda2": 0.8}``).

    The scenario is named after the vehicle: ``<vehicle>-<base name>``,
    ``vehicle`` defaulting to ``rotorpy-<mass in g>g`` (RotorPy's parameter
    dicts carry no name), e.g. ``rotorpy-500g-paper-scenario-1`` for the
    Hummingbird; an override of ``name`` wins."""
    scenario = base if base is not None else Scenario.builtin("paper-scenario-1")
    plant = {f"plant.{k}": v for k, v in plant_from_rotorpy(quad_params, aero).items()}
    if vehicle is None:
        vehicle = f"rotorpy-{round(float(quad_params['mass']) * 1000):d}g"
    named = {"name": f"{vehicle}-{scenario.name}"}
    return scenario.with_overrides({**named, **plant, **dict(overrides or {})})


class Controller:
    """An ftsmc controller with RotorPy's controller interface.

    ``name``: a registry name (``"ftaftsmc"``, ``"ranftsmc"``, …).
    ``quad_params``: the RotorPy vehicle's parameter dict; the controller's
    nominal model is built from it (:func:`scenario_for`) unless
    ``scenario`` is given, whose gains, ``[plant]`` and cascade settings are
    then used as they are.
    ``overrides``: dotted keys applied to the scenario.
    ``dt``: control period (s) of the first call; later calls use the time
    since the previous one (RotorPy calls once per simulator step).
    """

    def __init__(
        self,
        name: str = "ftaftsmc",
        quad_params: Optional[Mapping[str, Any]] = None,
        scenario: Optional[Scenario] = None,
        overrides: Optional[Mapping[str, Any]] = None,
        dt: Optional[float] = None,
        aero: bool = True,
    ) -> None:
        if scenario is None:
            if quad_params is None:
                raise ValueError("give the RotorPy vehicle's quad_params (or a scenario)")
            scenario = scenario_for(quad_params, overrides=overrides, aero=aero)
        elif overrides:
            scenario = scenario.with_overrides(overrides)
        self.name = name
        self.scenario: Scenario = scenario
        self._inner = _ftsmc.NativeController(name, scenario)
        self._dt_first = float(dt) if dt is not None else scenario.control_period
        self._t_last: Optional[float] = None
        self._psi_last: Optional[float] = None
        self._last: Dict[str, Any] = {}
        self._tm_to_f: Optional[np.ndarray] = None
        self._k_eta = 1.0
        if quad_params is not None:
            self._k_eta = float(quad_params["k_eta"])
            ratio = float(quad_params["k_m"]) / self._k_eta
            rotors = [np.asarray(r, dtype=float) for r in quad_params["rotor_pos"].values()]
            f_to_tm = np.vstack(
                (
                    np.ones(len(rotors)),
                    [r[1] for r in rotors],  # roll moment: (r x e_z)_x = r_y
                    [-r[0] for r in rotors],  # pitch moment: (r x e_z)_y = -r_x
                    ratio * np.asarray(quad_params["rotor_directions"], dtype=float),
                )
            )
            self._tm_to_f = np.linalg.inv(f_to_tm)

    def reset(self) -> None:
        """Restore the initial internal states (a new flight)."""
        self._inner.reset()
        self._t_last = None
        self._psi_last = None
        self._last = {}

    def state_of(self, state: Mapping[str, Any]) -> Tuple[float, ...]:
        """ftsmc's 12 state values (:class:`ftsmc.State` order) of a RotorPy state dict."""
        phi, theta, psi = euler_zyx(state["q"])
        if self._psi_last is not None:  # keep yaw continuous across ±π
            psi += 2.0 * math.pi * round((self._psi_last - psi) / (2.0 * math.pi))
        self._psi_last = psi
        rates = euler_rates(phi, theta, state["w"])
        x = np.asarray(state["x"], dtype=float)
        v = np.asarray(state["v"], dtype=float)
        return (x[0], x[1], x[2], phi, theta, psi, v[0], v[1], v[2], *rates)

    def update(self, t: float, state: Mapping[str, Any], flat_output: Mapping[str, Any]) -> Dict[str, Any]:
        """RotorPy's controller call: the control dict for time ``t`` (s)."""
        dt = self._dt_first if self._t_last is None else float(t) - self._t_last
        if dt <= 0.0 and self._last:
            return self._last  # called again at the same instant
        self._t_last = float(t)
        pos = np.asarray(flat_output["x"], dtype=float)
        vel = np.asarray(flat_output["x_dot"], dtype=float)
        acc = np.asarray(flat_output["x_ddot"], dtype=float)
        reference = (
            pos[0], pos[1], pos[2], vel[0], vel[1], vel[2], acc[0], acc[1], acc[2],
            float(flat_output.get("yaw", 0.0)),
            float(flat_output.get("yaw_dot", 0.0)),
            float(flat_output.get("yaw_ddot", 0.0)),
        )  # fmt: skip
        thrust, tx, ty, tz = self._inner.update(self.state_of(state), reference, dt)
        moment = np.array([tx, ty, tz])
        att_ref = self._inner.telemetry()[0]
        control: Dict[str, Any] = {
            "cmd_thrust": thrust,
            "cmd_moment": moment,
            "cmd_q": quaternion_zyx(att_ref[0], att_ref[1], att_ref[2]),
            "cmd_w": np.zeros(3),
            "cmd_v": vel,
            "cmd_acc": acc,
        }
        if self._tm_to_f is not None:
            forces = self._tm_to_f @ np.array([thrust, tx, ty, tz])
            speeds = forces / self._k_eta
            control["cmd_motor_thrusts"] = forces
            control["cmd_motor_speeds"] = np.sign(speeds) * np.sqrt(np.abs(speeds))
        self._last = control
        return control


def body_rates(phi: float, theta: float, euler_rates_: Sequence[float]) -> Tuple[float, float, float]:
    """Body rates ``(p, q, r)`` (rad/s) from Euler-angle rates ``(φ̇, θ̇, ψ̇)``
    (rad/s) at roll ``phi`` and pitch ``theta``: the inverse of
    :func:`euler_rates`, ``ω = W(φ, θ)⁻¹ (φ̇, θ̇, ψ̇)`` (ftsmc-core's
    ``kinematics::body_rates_from_euler_rates``)."""
    p, q, r = _ftsmc.kinematics_body_rates([phi, theta, 0.0], [float(v) for v in euler_rates_])
    return float(p), float(q), float(r)


class FromRotorPy:
    """A RotorPy controller flying in ftsmc's plant: the bridge the other way.

    ``ftsmc.simulate(scenario, FromRotorPy(rotorpy_controller))`` calls
    ``rotorpy_controller.update(t, state, flat_output)`` once per control
    period with ftsmc's state and reference in RotorPy's conventions
    (``q`` body-to-world ``[x, y, z, w]``, ``w`` body rates, rad/s;
    ``flat_output`` position, velocity, acceleration, yaw and its rates;
    jerk and snap are zero: ftsmc's references do not carry them) and flies
    its ``cmd_thrust`` (N) and ``cmd_moment`` (body torques, N·m), i.e.
    RotorPy's ``cmd_ctbm`` abstraction. The RotorPy controller should be
    built for the vehicle the scenario flies (:func:`scenario_for` gives a
    scenario for a RotorPy vehicle)."""

    def __init__(self, controller: Any, name: Optional[str] = None) -> None:
        self.controller = controller
        self.name: str = name or f"rotorpy-{type(controller).__name__}"
        self._t = 0.0

    def update(self, state: Any, reference: Any, dt: float) -> Any:
        """ftsmc's controller call: the command for one control period of ``dt`` s."""
        from . import Command

        phi, theta, psi = state.attitude
        rotorpy_state = {
            "x": np.asarray(state.position, dtype=float),
            "v": np.asarray(state.velocity, dtype=float),
            "q": quaternion_zyx(phi, theta, psi),
            "w": np.asarray(body_rates(phi, theta, state.angular_rate)),
            "wind": np.zeros(3),
            "rotor_speeds": np.zeros(4),
        }
        flat_output = {
            "x": np.asarray(reference.position, dtype=float),
            "x_dot": np.asarray(reference.velocity, dtype=float),
            "x_ddot": np.asarray(reference.acceleration, dtype=float),
            "x_dddot": np.zeros(3),
            "x_ddddot": np.zeros(3),
            "yaw": float(reference.yaw),
            "yaw_dot": float(reference.yaw_rate),
            "yaw_ddot": float(reference.yaw_acceleration),
        }
        control = self.controller.update(self._t, rotorpy_state, flat_output)
        self._t += dt
        moment = np.asarray(control["cmd_moment"], dtype=float).reshape(3)
        return Command(float(control["cmd_thrust"]), (float(moment[0]), float(moment[1]), float(moment[2])))


def from_rotorpy(controller: Any, name: Optional[str] = None) -> FromRotorPy:
    """:class:`FromRotorPy` around ``controller`` (a RotorPy controller object)."""
    return FromRotorPy(controller, name)
