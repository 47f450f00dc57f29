"""What the tests share: the project's root and the `oeg` command."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def oeg_binary() -> Path:
    """The `oeg` command: $OEG_BIN, else the workspace's release or debug build."""
    candidates = [os.environ.get("OEG_BIN", "")] + [str(ROOT / "target" / p / "oeg") for p in ("release", "debug")]
    for c in candidates:
        if c and Path(c).is_file():
            return Path(c)
    pytest.fail("no oeg binary: build it with `cargo build` or set OEG_BIN")


def run_cli(*args: str, check: bool = True) -> str:
    """Runs `oeg` in the project's root; its standard output."""
    done = subprocess.run([str(oeg_binary()), *args], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0 or not check, done.stderr
    return done.stdout
