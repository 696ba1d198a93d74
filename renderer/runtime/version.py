"""Lantern's version, as pyproject.toml declares it."""
from __future__ import annotations

import tomllib
from importlib import metadata
from pathlib import Path

PYPROJECT = Path(__file__).resolve().parents[2] / "pyproject.toml"


def lantern_version() -> str:
    """The version in the source tree's pyproject.toml (an editable install's metadata keeps the
    version of the day it was installed); the installed package's when there is no source tree."""
    try:
        with PYPROJECT.open("rb") as f:
            return str(tomllib.load(f)["project"]["version"])
    except (OSError, KeyError, tomllib.TOMLDecodeError):
        return metadata.version("lantern")
