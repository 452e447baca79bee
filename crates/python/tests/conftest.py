"""Shared fixtures of the Python test suite (pytest). Run from the repository root:
``.venv/bin/pip install ./crates/python && .venv/bin/pytest -q crates/python/tests``.

Other test modules (e.g. the ``.usda`` checks with Pixar's ``usd-core``) live here too."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def repo() -> Path:
    """The repository root."""
    return REPO


@pytest.fixture(scope="session")
def cli() -> Path:
    """The ``coiffure`` command line, built in release mode from the same sources as the package (the build
    is a no-op when up to date; ``COIFFURE_BIN`` overrides it)."""
    if "COIFFURE_BIN" in os.environ:
        return Path(os.environ["COIFFURE_BIN"])
    subprocess.run(["cargo", "build", "--release", "-q", "-p", "coiffure-server", "--bin", "coiffure"], cwd=REPO, check=True)
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "release" / "coiffure"
