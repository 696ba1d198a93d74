"""One frame of the user's input, read from GGUI's window (or made up by a test): keys pressed and
released in order, Control's chords, movement keys and mouse buttons held, the cursor."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import taichi as ti

MOVEMENT_KEYS = ("w", "a", "s", "d", "q", "e")


@dataclass(frozen=True)
class FrameInput:
    """One frame of user input, as GGUI reports it (or as a test makes it up).

    pressed: keys pressed since the last frame, GGUI names ('p', 'Escape', 'LMB'...).
    held:    movement keys held now, lower case ('w', ..., 'shift').
    cursor:  GGUI cursor position, [0, 1]^2 with the origin at the bottom left; None = unknown.
    buttons: mouse buttons held now ('LMB', 'RMB').
    """

    pressed: tuple[str, ...] = ()
    held: frozenset = frozenset()
    cursor: Optional[tuple[float, float]] = None
    buttons: frozenset = frozenset()
    released: tuple[str, ...] = ()  # keys and buttons released since the last frame ('LMB': a click ends)
    down: frozenset = frozenset()  # keys and buttons down at the end of the frame (poll_input's reading)

    @property
    def ctrl(self) -> bool:
        """Control down at the end of the frame (keys pressed with it came as "ctrl+z")."""
        return ti.ui.CTRL in self.down


def poll_input(window, before: Optional[FrameInput] = None) -> FrameInput:
    """This frame's input, after the last frame's. GGUI's events are read in order, presses and
    releases together (an event gives its key, not its kind: a press where the key was up, else a
    release), so a key pressed while Control is down comes as "ctrl+<key>" however the frames
    fall: ctrl+s whose `s` lands in the next frame is a chord; `p` right after ctrl+s is not."""
    before = before or FrameInput()
    down = set(before.down)
    pressed, released = [], []
    for event in window.get_events():  # every kind, in order
        key = event.key
        if key in down:
            down.discard(key)
            released.append(key)
        else:
            down.add(key)
            if key != ti.ui.CTRL:
                pressed.append(f"ctrl+{key}" if ti.ui.CTRL in down else key)
    # what is down now, asked of the window (a release may not arrive as an event, e.g. on losing focus)
    down = {key for key in down | {ti.ui.CTRL} if window.is_pressed(key)}
    held = {k for k in MOVEMENT_KEYS if window.is_pressed(k)}
    if window.is_pressed(ti.ui.SHIFT):
        held.add("shift")
    buttons = frozenset(b for b in (ti.ui.LMB, ti.ui.RMB) if window.is_pressed(b))
    x, y = window.get_cursor_pos()
    return FrameInput(tuple(pressed), frozenset(held), (float(x), float(y)), buttons, tuple(released),
                      frozenset(down))
