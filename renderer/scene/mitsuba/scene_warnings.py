"""The Mitsuba reader's warnings: one line naming file, line and plugin for what Lantern leaves out
or approximates (the modules that map plugins share them)."""
from __future__ import annotations

import warnings

from renderer.scene.mitsuba.plugins import Plugin


class MitsubaSceneWarning(UserWarning):
    """Something a Mitsuba scene asks for that Lantern leaves out or approximates."""


def warn(plugin: Plugin, message: str) -> None:
    warnings.warn(f"{plugin.where()}: {plugin.label()}: {message}", MitsubaSceneWarning, stacklevel=3)


def leave_out(plugin: Plugin, message: str) -> None:
    """One warning for a plugin left out whole (its parameters are not listed one by one)."""
    plugin.used.update(plugin.properties)
    warn(plugin, message)
