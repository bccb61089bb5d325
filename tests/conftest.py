"""Shared fixtures: where ../shared is, and a clean environment for launch resolution."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parent.parent
SHARED = REPO.parent / "shared"
COMPAT = SHARED / "compat"


@pytest.fixture
def compat_dir() -> Path:
    if not COMPAT.is_dir():
        pytest.skip("../shared/compat is not beside the repository")
    return COMPAT
