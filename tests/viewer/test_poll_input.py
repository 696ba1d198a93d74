"""How the viewer reads a frame's keys from GGUI's events (viewer/window.py poll_input): Control's
chords when a press and its release fall in different frames, and a key typed right after one."""
from types import SimpleNamespace

import taichi as ti

from viewer.window import poll_input


class FakeWindow:
    """One frame of GGUI's answers: the key presses and releases queued since the last frame, and
    the keys down at its end."""

    def __init__(self, presses=(), releases=(), down=()):
        self.events = {ti.ui.PRESS: [SimpleNamespace(key=k) for k in presses],
                       ti.ui.RELEASE: [SimpleNamespace(key=k) for k in releases]}
        self.down = set(down)

    def get_events(self, kind):
        return self.events[kind]

    def is_pressed(self, key):
        return key in self.down

    def get_cursor_pos(self):
        return 0.5, 0.5


def frames(*windows):
    """The FrameInputs of consecutive frames."""
    out, before = [], None
    for window in windows:
        before = poll_input(window, before)
        out.append(before)
    return out


CTRL = ti.ui.CTRL


def test_a_chord_whose_key_comes_in_the_next_frame_is_still_a_chord():
    held, chord = frames(FakeWindow([CTRL], down=[CTRL]), FakeWindow(["s"], [CTRL, "s"]))
    assert held.pressed == () and held.ctrl
    assert chord.pressed == ("ctrl+s",) and not chord.ctrl


def test_a_key_typed_as_control_is_released_after_a_chord_is_plain():
    """ctrl+s, then p in the frame where Control comes up: p (the viewer's screenshot), not ctrl+p."""
    chord, after = frames(FakeWindow([CTRL, "s"], down=[CTRL]), FakeWindow(["p"], [CTRL, "s"]))
    assert chord.pressed == ("ctrl+s",) and chord.chorded
    assert after.pressed == ("p",) and not after.ctrl and not after.chorded


def test_control_held_down_makes_every_key_a_chord():
    first, idle, second = frames(FakeWindow([CTRL, "z"], ["z"], down=[CTRL]), FakeWindow(down=[CTRL]),
                                 FakeWindow(["z"], ["z"], down=[CTRL]))
    assert (first.pressed, idle.pressed, second.pressed) == (("ctrl+z",), (), ("ctrl+z",))
    assert idle.chorded and second.chorded


def test_control_pressed_again_in_the_frame_it_is_released_starts_a_new_chord():
    """Released and pressed again within one frame, with a key: a new chord, whatever came before."""
    first, again = frames(FakeWindow([CTRL, "s"], down=[CTRL]), FakeWindow([CTRL, "z"], [CTRL, "s"], down=[CTRL]))
    assert first.pressed == ("ctrl+s",)
    assert again.pressed == ("ctrl+z",) and again.chorded
