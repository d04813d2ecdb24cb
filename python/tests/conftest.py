"""Shared fixtures of the Python package's tests: the CLI to compare with, the sample maps, a
temporary folder. Run by tools/test.sh after the wheel is installed into .venv."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def specmap_bin() -> str:
    """The CLI built from the same tree (SPECMAP_BIN, else target/debug/specmap)."""
    path = os.environ.get("SPECMAP_BIN", str(ROOT / "target" / "debug" / "specmap"))
    if not Path(path).is_file():
        pytest.fail(f"{path} is missing: run `cargo build` first (or set SPECMAP_BIN)")
    return path


@pytest.fixture(scope="session")
def cli(specmap_bin):
    """Runs `specmap ARGS...` and returns its stdout (parsed when --json is among ARGS)."""

    def run(*args):
        out = subprocess.run(
            [specmap_bin, *map(str, args)], check=True, capture_output=True, text=True
        ).stdout
        return json.loads(out) if "--json" in args else out

    return run


@pytest.fixture(scope="session")
def sunrise() -> str:
    return str(ROOT / "envmaps" / "sunrise.exr")


@pytest.fixture(scope="session")
def forest() -> str:
    return str(ROOT / "envmaps" / "forest.exr")
