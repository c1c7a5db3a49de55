"""Flight logs, identification and validation (docs/logs.md, docs/validation.md).

``read_log`` gives a log as a DataFrame in the generic CSV schema's column
names; ``identify`` and ``validate`` run ``ftsmc identify`` and ``ftsmc
validate`` and return their tables as DataFrames (the same numbers, to the
bit, as the CSV files the CLI writes). The computations are Rust's.
"""

from __future__ import annotations

import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Dict, Optional, Sequence, Union

from . import _ftsmc

if TYPE_CHECKING:
    import pandas

__all__ = ["Identification", "identify", "read_log", "synthetic_log", "validate"]

PathLike = Union[str, Path]


def read_log(path: PathLike) -> "pandas.DataFrame":
    """The flight log at ``path`` (PX4 ULog, NanoBench CSV or the generic CSV).

    Columns (only the channels the log has): ``time_s`` (s since the first
    sample), ``x_m y_m z_m`` (m), ``vx_m_s vy_m_s vz_m_s`` (m/s), ``qw qx qy
    qz`` (body → world), ``p_rad_s q_rad_s r_rad_s`` (rad/s, body),
    ``ax_m_s2 ay_m_s2 az_m_s2`` (specific force, m/s², body), ``motor1`` …
    ``motor4`` (in ``attrs["motor_unit"]``) and ``battery_v`` (V), in the
    log's own frame: ``attrs["frame"]`` is ``"ned-frd"`` (PX4),
    ``"zup-flu"`` (NanoBench) or ``"unspecified"``. ``attrs`` also holds
    ``source`` and ``time_origin_s`` (the first sample on the log's clock).
    A bad log raises ``ValueError`` naming the file and what is wrong.
    """
    import pandas

    names, columns, (source, frame, origin, unit) = _ftsmc.log_columns(str(path))
    df = pandas.DataFrame(dict(zip(names, columns)))
    df.attrs.update({"source": source, "frame": frame, "time_origin_s": origin, "motor_unit": unit})
    return df


@dataclass(frozen=True)
class Identification:
    """What ``identify`` found.

    ``vehicle_toml``: a vehicle file the simulator flies (``Scenario.from_file``
    of it after writing it, or ``extends`` from a scenario). ``parameters``:
    one row per quantity, columns ``name unit value lo hi basis base`` (the
    95 % bootstrap interval ``lo``–``hi``; ``base`` the base vehicle's value).
    ``report``: the whole identification as the CLI's ``identification.json``.
    """

    vehicle_toml: str
    parameters: "pandas.DataFrame"
    report: Dict[str, Any]


def identify(
    logs: Sequence[PathLike],
    vehicle: str = "crazyflie-2.1",
    mass: Optional[float] = None,
    bootstrap: int = 200,
    seed: int = 0,
    segment: float = 2.0,
    max_delay: int = 5,
) -> Identification:
    """``ftsmc identify``: the vehicle parameters the logs determine, with intervals.

    ``vehicle``: the base vehicle, a preset name or a vehicle/scenario file;
    ``mass`` (kg, default the base vehicle's) is what forces, inertias and
    drags need; ``segment`` (s) the bootstrap's segment length; ``max_delay``
    the largest command delay tried (log steps).
    """
    import pandas

    toml, csv, report = _ftsmc.log_identify(
        [str(p) for p in logs], vehicle, mass, bootstrap, seed, segment, max_delay
    )
    return Identification(toml, pandas.read_csv(io.StringIO(csv)), json.loads(report))


def validate(
    logs: Sequence[PathLike],
    vehicle: str,
    bootstrap: int = 200,
    seed: int = 0,
    command_delay: int = 0,
) -> "pandas.DataFrame":
    """``ftsmc validate``: the plant's open-loop predictions against the logs.

    One row per flight (and ``"all"``, pooled), horizon (``horizon_s``: one
    step, 0.1 s, 0.5 s), quantity (``specific_force`` m/s²,
    ``angular_acceleration`` rad/s²) and axis: ``r2`` with its 95 % interval
    ``r2_lo``–``r2_hi``, ``rms`` with ``rms_lo``–``rms_hi``, and the
    constant-acceleration baseline's ``baseline_r2`` and ``baseline_rms``.
    """
    import pandas

    csv = _ftsmc.log_validate([str(p) for p in logs], vehicle, bootstrap, seed, command_delay)
    return pandas.read_csv(io.StringIO(csv))


def synthetic_log(
    vehicle: str = "crazyflie-2.1",
    duration_s: float = 12.0,
    accel_noise: float = 0.0,
    gyro_noise: float = 0.0,
    seed: int = 0,
) -> str:
    """A flight made by ftsmc's own plant (dithered hover), as generic CSV text.

    Its parameters are known (those of ``vehicle``), so ``identify`` should
    recover them and ``validate`` of a noise-free flight gives R² = 1; write
    it to a ``.csv`` file to read it back. Noise: accelerometer σ in m/s²,
    gyro σ in rad/s.
    """
    return _ftsmc.log_synthetic(vehicle, duration_s, accel_noise, gyro_noise, seed)
