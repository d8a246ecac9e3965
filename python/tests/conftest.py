"""Shared fixtures: the bundled meshes and the command-line binary to compare with."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MESHES = ROOT / "assets" / "meshes"
BUNNY = MESHES / "bunny.obj"
SPOT = MESHES / "spot.obj"
FOURLEG = MESHES / "fourleg_2.obj"


def _find_cli() -> Path | None:
    env = os.environ.get("BVSEG_CLI")
    if env:
        return Path(env)
    for candidate in (ROOT / "target" / "release" / "bvseg", shutil.which("bvseg")):
        if candidate and Path(candidate).is_file():
            return Path(candidate)
    return None


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `bvseg` binary: $BVSEG_CLI, else target/release/bvseg, else one on PATH. Under CI
    (CI set) a missing binary fails the test rather than skipping it."""
    path = _find_cli()
    if path is None or not path.is_file():
        msg = (
            f"the bvseg command-line binary was not found (BVSEG_CLI={os.environ.get('BVSEG_CLI')!r}, "
            f"no {ROOT / 'target/release/bvseg'}); build it with `cargo build --release -p bvseg-cli`"
        )
        if os.environ.get("CI"):
            pytest.fail(msg)
        pytest.skip(msg)
    return path


@pytest.fixture(scope="session")
def run_cli(cli: Path):
    """Runs `bvseg ARGS...` from the repository root; returns the completed process."""

    def run(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
        p = subprocess.run([str(cli), *args], cwd=ROOT, capture_output=True, text=True)
        if check and p.returncode != 0:
            raise AssertionError(f"bvseg {' '.join(args)} exited {p.returncode}: {p.stderr}")
        return p

    return run
