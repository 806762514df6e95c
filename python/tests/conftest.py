"""Shared fixtures: a small scene and the command-line programs."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

import littoral

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture
def small() -> littoral.Scene:
    """The repository's minimal scene (4 bands, 1000 photons) on 16 x 12 pixels."""
    return littoral.Scene.from_toml(REPO / "tests/scenes/minimal.toml").with_(
        {"sensor.pixels": [16, 12]}
    )


def _bin_dir() -> Path:
    named = os.environ.get("LITTORAL_BIN_DIR")
    if named:
        return Path(named)
    built = [REPO / "target" / p for p in ("debug", "release") if (REPO / "target" / p / "littoral").is_file()]
    if not built:
        pytest.fail("no littoral binary: run `cargo build` or set LITTORAL_BIN_DIR")
    return max(built, key=lambda p: (p / "littoral").stat().st_mtime)


@pytest.fixture
def cli() -> Path:
    """The directory holding the `littoral` and `littoral-cube` programs."""
    d = _bin_dir()
    for name in ("littoral", "littoral-cube"):
        if not (d / name).is_file() or shutil.which(str(d / name)) is None:
            pytest.fail(f"{d / name}: not built")
    return d
