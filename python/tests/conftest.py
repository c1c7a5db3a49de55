"""Shared fixtures: the `ftsmc` binary built from this repository."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def _find_cli() -> Path:
    """$FTSMC_BIN, else target/release/ftsmc, else target/debug/ftsmc."""
    env = os.environ.get("FTSMC_BIN")
    if env:
        return Path(env)
    for profile in ("release", "debug"):
        candidate = REPO / "target" / profile / "ftsmc"
        if candidate.is_file():
            return candidate
    raise RuntimeError(
        "no ftsmc binary: set FTSMC_BIN or build it (cargo build -p ftsmc-cli); "
        "the byte-identity tests compare against it"
    )


@pytest.fixture(scope="session")
def cli() -> Path:
    path = _find_cli()
    assert path.is_file(), f"FTSMC_BIN={path} is not a file"
    return path


def run_cli(cli: Path, *args: str) -> None:
    """Run the CLI, failing the test with its stderr on a non-zero exit."""
    done = subprocess.run([str(cli), *args], capture_output=True, text=True)
    assert done.returncode == 0, f"ftsmc {' '.join(args)} failed:\n{done.stderr}"
