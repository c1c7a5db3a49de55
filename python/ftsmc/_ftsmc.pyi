# Hand-written stub of the native module ftsmc._ftsmc (crates/ftsmc-py).
# Keep in step with crates/ftsmc-py/src/*.rs; `mypy --strict` checks the
# package and the examples against it.
from os import PathLike
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

class Scenario:
    """A validated scenario (docs/scenarios.md). Errors raise ValueError with the CLI's message."""

    @staticmethod
    def builtin(name: str) -> Scenario:
        """A built-in scenario by name (``.toml`` optional): any of :meth:`builtin_names`; an unknown name is a ``ValueError`` listing them all."""
    @staticmethod
    def builtin_names() -> List[str]:
        """The names of every built-in scenario, in ``ftsmc list`` order."""
    @staticmethod
    def from_file(path: Union[str, PathLike[str]]) -> Scenario:
        """Read, resolve (``extends``) and validate a scenario file."""
    @staticmethod
    def from_toml(text: str, path: str = "<string>") -> Scenario:
        """Parse and validate TOML text (``path`` names it in messages)."""
    def to_toml(self) -> str:
        """The resolved scenario as TOML (the CLI's ``scenario.toml``)."""
    def with_overrides(self, overrides: Mapping[str, Any]) -> Scenario:
        """A new validated scenario with dotted keys set, e.g. ``{"payload.mass": 0.5}``."""
    @property
    def name(self) -> str: ...
    @property
    def tune_mission(self) -> Optional[str]:
        """The mission a tuned file states (``[tune] mission``), None when it states none."""
    @property
    def description(self) -> str: ...
    @property
    def duration(self) -> float:
        """Simulated time, s."""
    @property
    def seed(self) -> int: ...
    @property
    def controllers(self) -> List[str]: ...
    @property
    def control_period(self) -> float:
        """1 / ``simulation.control_rate``, s."""
    @property
    def has_montecarlo(self) -> bool: ...
    def __eq__(self, other: object) -> bool: ...

class NativeController:
    def __init__(self, name: str, scenario: Scenario) -> None: ...
    @property
    def name(self) -> str: ...
    def update(self, state: Sequence[float], reference: Sequence[float], dt: float) -> Tuple[float, float, float, float]:
        """Raises ValueError naming the field of a NaN or infinite state or reference value (not updated)."""
    def reset(self) -> None: ...
    def telemetry(
        self,
    ) -> Tuple[List[float], List[float], Optional[List[float]], Optional[float]]: ...

class RunData:
    @property
    def controller(self) -> str: ...
    @property
    def scenario(self) -> str: ...
    @property
    def steps(self) -> int: ...
    def exit_json(self) -> str: ...
    def exit_text(self) -> str: ...
    def metrics_json(self) -> str: ...
    def column_names(self) -> List[str]: ...
    def columns(self) -> List[npt.NDArray[np.float64]]: ...
    def csv(self) -> bytes: ...

class GymBatch:
    """N environments of one scenario stepped in Rust (ftsmc.gym)."""

    def __init__(
        self,
        scenario: Scenario,
        seeds: Sequence[int],
        task: str = "track",
        target: Optional[Sequence[float]] = None,
        action: str = "ctbr",
        observe: str = "sensors",
        agent_rate: float = 100.0,
        max_episode_time: Optional[float] = None,
        reward: Optional[Mapping[str, float]] = None,
        rate_gain: Optional[Sequence[float]] = None,
        max_rate: Optional[Sequence[float]] = None,
        randomize: bool = False,
        hover_radius: Optional[float] = None,
    ) -> None: ...
    @property
    def num_envs(self) -> int: ...
    def pose(self, i: int) -> Tuple[List[float], List[float], List[float]]: ...
    def reset(self, seeds: npt.NDArray[np.uint64]) -> _GymOut: ...
    def step(self, actions: npt.NDArray[np.float64], reset_seeds: npt.NDArray[np.uint64]) -> _GymOut: ...
    def done(self) -> npt.NDArray[np.bool_]: ...
    def seeds(self) -> npt.NDArray[np.uint64]: ...
    @property
    def step_time(self) -> float: ...
    @property
    def episode_time(self) -> float: ...
    @property
    def max_position_error(self) -> float: ...
    @property
    def max_thrust(self) -> float: ...
    @property
    def rotor_speed_range(self) -> Tuple[float, float]: ...
    @property
    def mass(self) -> float: ...
    @property
    def max_rate(self) -> List[float]: ...
    @property
    def reward_weights(self) -> Dict[str, float]: ...
    @staticmethod
    def observation_names() -> List[str]: ...

_GymOut = Tuple[
    npt.NDArray[np.float32],
    npt.NDArray[np.float64],
    npt.NDArray[np.bool_],
    npt.NDArray[np.bool_],
    List[str],
    npt.NDArray[np.float64],
    npt.NDArray[np.bool_],
]

# The campaign defaults (ftsmc_sim::defaults): run counts and budgets as int, confidence as float.
DEFAULTS: Dict[str, Union[int, float]]

class NativeTrajectory:
    """A built trajectory (crates/ftsmc-py/src/trajectory.rs); ``ftsmc.Trajectory`` wraps it."""

    @staticmethod
    def min_snap(
        waypoints: npt.NDArray[np.float64],
        yaw: Optional[npt.NDArray[np.float64]] = None,
        speed: Optional[float] = None,
        duration: Optional[float] = None,
        times: Optional[npt.NDArray[np.float64]] = None,
        start: Optional[float] = None,
        min_segment_time: Optional[float] = None,
    ) -> NativeTrajectory: ...
    @staticmethod
    def shape(kind: str, params: Optional[Mapping[str, Any]] = None) -> NativeTrajectory: ...
    @staticmethod
    def shape_names() -> List[str]: ...
    @property
    def kind(self) -> str: ...
    @property
    def start(self) -> float: ...
    @property
    def end(self) -> Optional[float]: ...
    def knot_times(self) -> Optional[npt.NDArray[np.float64]]: ...
    def snap_cost(self, o: int) -> Optional[float]: ...
    def sample(
        self, t: npt.NDArray[np.float64]
    ) -> Tuple[
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
        npt.NDArray[np.float64],
    ]: ...
    def to_toml(self) -> str: ...
    def into_scenario(self, scenario: Scenario, time_scale: str = "fixed", start_on_it: bool = True) -> Scenario: ...

def vehicle_arm_length(scenario: Scenario) -> float: ...
def simulate_native(scenario: Scenario, controller: str) -> RunData: ...
def simulate_python(scenario: Scenario, controller: Any, state_cls: Any, reference_cls: Any, name: str) -> RunData: ...
def gym_check_envs(scenario: Scenario, num_envs: int) -> None: ...
def montecarlo_columns(
    scenario: Scenario,
    runs: int,
    seed: Optional[int] = None,
    controllers: Optional[List[str]] = None,
    threads: Optional[int] = None,
    run_range: Optional[Tuple[int, int]] = None,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Tuple[List[str], List[Union[npt.NDArray[Any], List[str]]]]: ...
def tune_native(
    scenario: Scenario,
    controller: str,
    budget: int = 2000,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    extends: Optional[str] = None,
    evaluator: Optional[Callable[[List[str], List[int]], List[List[float]]]] = None,
    mission: Optional[str] = None,
) -> Tuple[Scenario, str, str]: ...
def falsify_native(
    scenario: Scenario,
    controller: str,
    budget: int = 200,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> str: ...
def failure_probability_native(
    scenario: Scenario,
    controller: str,
    budget: int = 2000,
    confidence: float = 0.95,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
) -> str: ...
def tune_evaluate(
    tomls: List[str],
    controller: str,
    master: int,
    indices: List[int],
    threads: Optional[int] = None,
) -> List[List[float]]: ...
def compare_native(
    scenario: Scenario,
    contestants: List[Any],
    runs: int,
    until_decided: bool,
    batch: int,
    max_runs: int,
    confidence: float,
    seed: Optional[int] = None,
    threads: Optional[int] = None,
    allow_other_vehicle: bool = False,
    progress: Optional[Callable[[int, int], Any]] = None,
) -> Tuple[
    Tuple[List[str], List[Union[npt.NDArray[Any], List[str]]]],
    List[str],
    List[List[Tuple[str, float]]],
    List[Tuple[Tuple[str, str, str, str], Tuple[int, float, float, float, float, float]]],
    int,
    bool,
]: ...
def stats_intervals(
    success: Sequence[bool], completed: Sequence[bool], crashed: Sequence[bool], rms: Sequence[float], confidence: float
) -> List[Tuple[str, float]]: ...
def stats_wilson(k: int, n: int, confidence: float) -> Tuple[float, float, float]: ...
def stats_clopper_pearson(k: int, n: int, confidence: float) -> Tuple[float, float, float]: ...
def stats_binomial_quantile(prob: float, n: int, p: float) -> int: ...
def stats_mcnemar_exact(b: int, c: int) -> float: ...
def stats_wilcoxon(diffs: Sequence[float]) -> Tuple[float, float, float, bool]: ...
def kinematics_euler_from_quaternion(q: Sequence[float]) -> Any: ...
def kinematics_quaternion_from_euler(euler: Sequence[float]) -> Any: ...
def kinematics_euler_rates(euler: Sequence[float], body_rates: Sequence[float]) -> Any: ...
def kinematics_body_rates(euler: Sequence[float], euler_rates: Sequence[float]) -> Any: ...
def controller_names() -> List[Tuple[str, str]]: ...
def controller_label(name: str) -> str: ...
def check_controllers(argument: str, names: List[str]) -> None: ...
def log_columns(path: str) -> Tuple[List[str], List[npt.NDArray[Any]], Tuple[str, str, float, Optional[str]]]: ...
def log_identify(
    logs: List[str], vehicle: str, mass: Optional[float], bootstrap: int, seed: int, segment: float, max_delay: int
) -> Tuple[str, str, str]: ...
def log_validate(logs: List[str], vehicle: str, bootstrap: int, seed: int, command_delay: int) -> str: ...
def log_synthetic(vehicle: str, duration_s: float, accel_noise: float, gyro_noise: float, seed: int) -> str: ...
