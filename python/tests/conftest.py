"""Shared fixtures: the `ftsmc` binary built from this repository.

The byte-identity tests compare the Python package against the CLI built
from the same sources. With no environment variable set, the binary is found
in Cargo's target folder (``$CARGO_TARGET_DIR`` or ``target/``, release then
debug) or built there with ``cargo build --release -p ftsmc-cli`` (the
release profile ``pip install ./python`` already compiled); an ``ftsmc`` on
``PATH`` is the last resort (it may be another version).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Iterator, List

import pytest

REPO = Path(__file__).resolve().parents[2]


def _target_dirs() -> List[Path]:
    dirs = []
    env = os.environ.get("CARGO_TARGET_DIR")
    if env:
        dirs.append(Path(env) if Path(env).is_absolute() else REPO / env)
    dirs.append(REPO / "target")
    return dirs


def _built() -> List[Path]:
    return [d / profile / "ftsmc" for d in _target_dirs() for profile in ("release", "debug")]


def _find_cli() -> Path:
    """$FTSMC_BIN; else the first of $CARGO_TARGET_DIR or target/ (release,
    debug) that holds a binary; else build it; else `ftsmc` on PATH."""
    env = os.environ.get("FTSMC_BIN")
    if env:
        return Path(env)
    for candidate in _built():
        if candidate.is_file():
            return candidate
    cargo = shutil.which("cargo")
    if cargo is not None and (REPO / "Cargo.toml").is_file():
        done = subprocess.run(
            [cargo, "build", "--release", "--locked", "-p", "ftsmc-cli"], cwd=REPO, capture_output=True, text=True
        )
        if done.returncode != 0:
            raise RuntimeError(f"cargo build --release -p ftsmc-cli failed:\n{done.stderr[-4000:]}")
        for candidate in _built():
            if candidate.is_file():
                return candidate
    installed = shutil.which("ftsmc")
    if installed is not None:
        return Path(installed)
    raise RuntimeError(
        "no ftsmc binary: set FTSMC_BIN, or install Rust (cargo) so the tests can build it "
        "(cargo build --release -p ftsmc-cli); the byte-identity tests compare against it"
    )


@pytest.fixture(scope="session", autouse=True)
def temp_dir_inside_pytests_own(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Path]:
    """The temporary folder of the test session, and of every process it
    starts (the CLI, the examples, Dask's scheduler and worker processes),
    is a folder inside pytest's base temp, which pytest prunes to the last
    three runs: what the tests and the libraries they call write to the
    temporary folder (Dask's ``dask-scratch-space``, the folder of a worker
    killed on purpose) does not pile up in the system's temporary folder."""
    tmp = tmp_path_factory.mktemp("tmp")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("TMPDIR", str(tmp))
        mp.setattr(tempfile, "tempdir", str(tmp))
        yield tmp


@pytest.fixture(scope="session")
def cli() -> Path:
    path = _find_cli()
    assert path.is_file(), f"FTSMC_BIN={path} is not a file"
    return path


def run_cli(cli: Path, *args: str) -> None:
    """Run the CLI, failing the test with its stderr on a non-zero exit."""
    done = subprocess.run([str(cli), *args], capture_output=True, text=True)
    assert done.returncode == 0, f"ftsmc {' '.join(args)} failed:\n{done.stderr}"
