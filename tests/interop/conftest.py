"""Shared helpers: run the specmap binary and parse its JSON."""
import json
import os
import pathlib
import subprocess
import warnings

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
BIN = os.environ.get("SPECMAP_BIN", str(ROOT / "target" / "debug" / "specmap"))

warnings.filterwarnings("ignore")  # colour-science warns about aligning shapes; that is expected


def specmap_json(*args):
    """Runs `specmap ARGS --json` and returns the parsed output; fails with its stderr."""
    p = subprocess.run([BIN, *args, "--json"], capture_output=True, text=True)
    if p.returncode != 0:
        pytest.fail(f"specmap {' '.join(args)} exited {p.returncode}: {p.stderr}")
    return json.loads(p.stdout)


@pytest.fixture(scope="session")
def specmap():
    if not pathlib.Path(BIN).exists():
        pytest.fail(f"{BIN} is missing: build it first (cargo build)")
    return specmap_json
