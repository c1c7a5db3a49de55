"""ftsmc from Python: the FTAFTSMC quadrotor simulator and controllers.

The simulator, scenario loader and control laws are ftsmc's Rust code (the
same as the ``ftsmc`` command's), so results equal the CLI's for the same
scenario. See docs/python.md for the API and examples/python/ for scripts.

Conventions (ftsmc-core's ``QuadState``, ``Reference``, ``Command``): world
frame with z up, SI units; attitude as Z-Y-X Euler angles (roll φ, pitch θ,
yaw ψ) in rad; ``angular_rate`` holds the Euler-angle *rates* (φ̇, θ̇, ψ̇) in
rad/s, not body rates; thrust U1 along body z in N, torques about body x,
y, z in N·m.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Any, Dict, NamedTuple, Optional, Protocol, Sequence, Tuple, Union

import numpy as np

from . import _ftsmc, _progress
from ._frames import frame as _frame
from ._ftsmc import Scenario
from ._trajectory import SHAPES as TRAJECTORY_SHAPES
from ._trajectory import Trajectory, TrajectorySample, trajectory
from .logs import Identification, identify, read_log, validate

if TYPE_CHECKING:
    import matplotlib.figure
    import pandas

__all__ = [
    "CONTROLLERS",
    "Command",
    "Comparison",
    "Controller",
    "Exit",
    "PythonController",
    "Reference",
    "Run",
    "Scenario",
    "State",
    "Telemetry",
    "compare",
    "label",
    "montecarlo",
    "simulate",
    "tune",
    "falsify",
    "failure_probability",
    "Tuned",
    "TRAJECTORY_SHAPES",
    "Trajectory",
    "TrajectorySample",
    "trajectory",
    "Identification",
    "identify",
    "read_log",
    "validate",
]

__version__: str = _ftsmc.__version__

Vec3 = Tuple[float, float, float]
"""Three floats (a tuple; any sequence of three numbers is accepted as input)."""

CONTROLLERS: Dict[str, str] = dict(_ftsmc.controller_names())
"""Every controller ftsmc can build, name → one-line description (from the registry)."""


def label(name: str) -> str:
    """Human-readable label of controller ``name`` (``"FTAFTSMC"``, ``"RANFTSMC [19]"``)."""
    return _ftsmc.controller_label(name)


@dataclass
class State:
    """The vehicle state a controller sees (ftsmc-core ``QuadState``).

    position: ``(x, y, z)``, m, world frame, z up.
    attitude: ``(φ, θ, ψ)`` roll, pitch, yaw, rad, Z-Y-X Euler angles
        (body-to-world rotation ``R = Rz(ψ) Ry(θ) Rx(φ)``).
    velocity: ``(ẋ, ẏ, ż)``, m/s, world frame.
    angular_rate: Euler-angle rates ``(φ̇, θ̇, ψ̇)``, rad/s (not body rates;
        see ``ftsmc.rotorpy.euler_rates`` for the conversion).
    """

    position: Vec3 = (0.0, 0.0, 0.0)
    attitude: Vec3 = (0.0, 0.0, 0.0)
    velocity: Vec3 = (0.0, 0.0, 0.0)
    angular_rate: Vec3 = (0.0, 0.0, 0.0)


@dataclass
class Reference:
    """The desired trajectory at one instant (ftsmc-core ``Reference``).

    position, velocity, acceleration: ``x_d``, ``ẋ_d``, ``ẍ_d`` per world axis,
        m, m/s, m/s².
    yaw, yaw_rate, yaw_acceleration: ``ψ_d`` rad, ``ψ̇_d`` rad/s, ``ψ̈_d`` rad/s².
    Roll and pitch references are computed by the cascade (paper Eq. 52).
    """

    position: Vec3 = (0.0, 0.0, 0.0)
    velocity: Vec3 = (0.0, 0.0, 0.0)
    acceleration: Vec3 = (0.0, 0.0, 0.0)
    yaw: float = 0.0
    yaw_rate: float = 0.0
    yaw_acceleration: float = 0.0


@dataclass
class Command:
    """A control command (ftsmc-core ``Command``, paper Eq. 2).

    thrust: total thrust U1 along body z, N.
    torque: ``(u2, u3, u4)`` about body x (roll), y (pitch), z (yaw), N·m.
    """

    thrust: float = 0.0
    torque: Vec3 = (0.0, 0.0, 0.0)


@dataclass(frozen=True)
class Telemetry:
    """What a built-in controller computed at its last update.

    attitude_reference: ``(φ_ref, θ_ref, ψ_d)`` tracked by the attitude loop, rad.
    attitude_reference_rate: its rate, rad/s.
    sliding: sliding variables ``(S_x, S_y, S_z, S_φ, S_θ, S_ψ)`` of the
        sliding-mode controllers; ``None`` for ``pid`` and ``se3`` (no sliding surfaces).
    alpha_hat: mass-ratio estimate α̂ (estimated mass = α̂ · plant mass);
        ``None`` for ``pid`` and ``se3``.
    """

    attitude_reference: Vec3
    attitude_reference_rate: Vec3
    sliding: Optional[Tuple[float, float, float, float, float, float]]
    alpha_hat: Optional[float]


class CommandLike(Protocol):
    """Anything with ``thrust`` (N) and ``torque`` (three N·m values)."""

    @property
    def thrust(self) -> float: ...

    @property
    def torque(self) -> Sequence[float]: ...


class PythonController(Protocol):
    """A controller written in Python that ``simulate`` can fly.

    ``update`` is called once per control period (``1/simulation.control_rate``)
    with the measured state, the reference and the period ``dt`` (s) and
    returns the command held until the next call. An optional ``name``
    attribute names the run; an optional ``reset()`` is not called by ftsmc.
    """

    def update(self, state: State, reference: Reference, dt: float) -> CommandLike: ...


class Exit(NamedTuple):
    """How a run ended.

    status: ``"completed"``, ``"diverged"``, ``"crashed"`` or ``"grounded"``
    (rested on the ground longer than ``[ground] max_ground_time`` after take-off).
    time: s, when it stopped (the scenario's duration when completed).
    text: the CLI's wording (``summary.json``'s ``exit``).
    detail: ``summary.json``'s ``exit_status`` (with the divergence reason).
    """

    status: str
    time: float
    text: str
    detail: Dict[str, Any]


class Run:
    """One flight's results.

    exit: :class:`Exit` (status and time).
    metrics: the run's entry of the CLI's ``summary.json`` (same keys and
        values: ``ise``, ``iae``, …, ``exit``, ``steps``, ``covered``, ``completed``).
    columns: the CSV time series, column name → 1-D float64 array.
    arm_length: the flown vehicle's arm length, m (rotor centre to body
        centre; ``ftsmc.plot.animate`` draws it to scale), when known.
    """

    def __init__(self, data: _ftsmc.RunData) -> None:
        self._data = data
        self.controller: str = data.controller
        self.scenario: str = data.scenario
        self.steps: int = data.steps
        self.metrics: Dict[str, Any] = json.loads(data.metrics_json())
        detail: Dict[str, Any] = json.loads(data.exit_json())
        time = float(detail.get("time", self.metrics["duration"]))
        self.exit = Exit(str(detail["status"]), time, data.exit_text(), detail)
        self.arm_length: Optional[float] = None

    @cached_property
    def columns(self) -> Dict[str, np.ndarray]:
        """Column name → 1-D float64 array (the columns of the CLI's ``<controller>.csv``)."""
        return dict(zip(self._data.column_names(), self._data.columns()))

    def to_pandas(self) -> pandas.DataFrame:
        """The time series as a DataFrame (one column per CSV column)."""
        import pandas

        return pandas.DataFrame(self.columns)

    def to_csv(self) -> bytes:
        """The time series exactly as the CLI writes ``<controller>.csv``."""
        return self._data.csv()

    def plot(self, what: str = "all") -> matplotlib.figure.Figure:
        """A matplotlib figure of this run: ``"all"`` (position, attitude and
        rotor speeds, one row each), ``"position"``, ``"attitude"`` or
        ``"rotors"`` (see :mod:`ftsmc.plot`)."""
        from . import plot

        return plot.run(self, what)

    def __repr__(self) -> str:
        return f"Run(controller={self.controller!r}, scenario={self.scenario!r}, exit={self.exit.text!r})"


def simulate(scenario: Scenario, controller: Union[str, PythonController] = "ftaftsmc") -> Run:
    """Fly ``scenario`` with a built-in controller (registry name) or a Python one.

    A built-in controller flies with the GIL released. A Python controller
    (see :class:`PythonController`) is called once per control period; an
    exception it raises ends the flight and is re-raised here.
    Raises ValueError (the CLI's message) for an unknown name or a run over
    the scenario's cost limits.
    """
    if isinstance(controller, str):
        run = Run(_ftsmc.simulate_native(scenario, controller))
    else:
        name = getattr(controller, "name", None)
        if not isinstance(name, str):
            name = type(controller).__name__
        run = Run(_ftsmc.simulate_python(scenario, controller, State, Reference, name))
    run.arm_length = _ftsmc.vehicle_arm_length(scenario)
    return run


def montecarlo(
    scenario: Scenario,
    runs: int,
    seed: Optional[int] = None,
    controllers: Optional[Sequence[str]] = None,
    threads: Optional[int] = None,
    client: Optional[Any] = None,
    shards: Optional[int] = None,
    progress: _progress.ProgressArg = None,
) -> pandas.DataFrame:
    """A Monte Carlo batch: the rows of the CLI's ``runs.csv`` as a DataFrame.

    ``runs`` randomised copies of ``scenario`` (its ``[montecarlo]`` section)
    flown by each controller (default: the scenario's list), master seed
    ``seed`` (default: the scenario's ``seed``, as the CLI), on ``threads``
    workers (default: all cores; the rows do not depend on it), with the
    GIL released. Same rows and values as ``ftsmc montecarlo``: ``run``,
    ``seed`` and ``saturated_periods`` are uint64, empty CSV cells are NaN, ``completed``/``success``/
    ``crashed`` are bool, text columns are objects (None for an empty cell). ``progress`` (local batches): a tqdm bar (shown
    after 1 s) when the session is interactive and tqdm is installed
    (``None``), always (``True``), never (``False``), or a callable
    ``progress(done, total)`` (control steps), called about every 0.2 s.

    With ``client`` (a ``dask.distributed.Client``; ``pip install
    "./python[dask]"``) the batch is flown as ``shards`` Dask tasks of
    contiguous runs, ``threads`` (default 1) threads each, and gives the same
    rows; see :mod:`ftsmc.dask` and docs/campaigns.md.
    """
    import pandas

    if controllers is not None:
        if isinstance(controllers, str):
            controllers = [controllers]
        for c in controllers:
            if not isinstance(c, str):
                raise TypeError(
                    f"montecarlo flies built-in controllers by name ({', '.join(CONTROLLERS)}); "
                    f"got a {type(c).__name__} object. A Python controller runs under the GIL and cannot be flown "
                    "on the batch's worker threads: fly it with ftsmc.simulate(scenario.with_overrides({...}), "
                    "controller) in a loop over the parameters you want to vary"
                )

    names_arg = None if controllers is None else list(controllers)
    if names_arg is not None:
        # The library's check (as the CLI's -c): an empty list or name, an unknown name.
        _ftsmc.check_controllers("controllers", names_arg)
    if client is not None:
        from .dask import montecarlo_columns

        per_task = 1 if threads is None else threads
        names, columns = montecarlo_columns(client, scenario, runs, seed, names_arg, shards, per_task)
    else:
        if shards is not None:
            raise ValueError("shards needs a Dask client (client=...)")
        flights = runs * len(scenario.controllers if names_arg is None else names_arg)
        cb = _progress.callback(progress, flights, f"{scenario.name} Monte Carlo")
        try:
            names, columns = _ftsmc.montecarlo_columns(scenario, runs, seed, names_arg, threads, None, cb)
        finally:
            _progress.close(cb)
    return _frame(names, columns)


class Controller:
    """One of ftsmc's controllers, called step by step from any simulator.

    ``Controller("ftaftsmc", scenario)`` builds the controller with the
    scenario's gains, nominal model (``[plant]``) and cascade settings.
    """

    def __init__(self, name: str, scenario: Scenario) -> None:
        self._inner = _ftsmc.NativeController(name, scenario)
        self.name: str = name

    def update(self, state: State, reference: Reference, dt: float) -> Command:
        """One control period of ``dt`` s: the command for ``state`` and ``reference``.

        Every state and reference value must be finite: a NaN or infinite one
        raises :class:`ValueError` naming it (``Controller.update:
        state.position[1] is nan; ...``) and the controller is not updated
        (the laws themselves would return a NaN command without a word)."""
        s = (*state.position, *state.attitude, *state.velocity, *state.angular_rate)
        r = (
            *reference.position,
            *reference.velocity,
            *reference.acceleration,
            reference.yaw,
            reference.yaw_rate,
            reference.yaw_acceleration,
        )
        thrust, tx, ty, tz = self._inner.update(s, r, dt)
        return Command(thrust, (tx, ty, tz))

    def update_arrays(self, state: Sequence[float], reference: Sequence[float], dt: float) -> Tuple[float, float, float, float]:
        """:meth:`update` on flat sequences (12 state values in :class:`State`'s
        field order, 12 reference values in :class:`Reference`'s), returning
        ``(thrust, roll torque, pitch torque, yaw torque)``: no dataclasses.
        A NaN or infinite value raises :class:`ValueError` as in :meth:`update`
        (named by its :class:`State` or :class:`Reference` field)."""
        return self._inner.update(state, reference, dt)

    def reset(self) -> None:
        """Restore the initial internal states (adaptive gains, filters)."""
        self._inner.reset()

    @property
    def telemetry(self) -> Telemetry:
        """What the last update computed (attitude reference, sliding variables, α̂)."""
        att, rate, sliding, alpha = self._inner.telemetry()
        return Telemetry(
            tuple(att), tuple(rate), None if sliding is None else tuple(sliding), alpha  # type: ignore[arg-type]
        )

    def __repr__(self) -> str:
        return f"Controller({self.name!r})"


from . import plot  # noqa: E402  (``ftsmc.plot`` after ``import ftsmc``; matplotlib is imported when a figure is drawn)
from .comparing import Comparison, compare  # noqa: E402  (re-export; the code lives in comparing.py)
from .tuning import Tuned, tune  # noqa: E402  (re-export; the code lives in tuning.py)
from .falsification import failure_probability, falsify  # noqa: E402  (re-export; the code lives in falsification.py)
