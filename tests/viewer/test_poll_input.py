"""How the viewer reads a frame's keys from GGUI's events (viewer/frame_input.py poll_input): the
events in order, Control's chords when a press and its release fall in different frames, and a key
typed right after one."""
from types import SimpleNamespace

import taichi as ti

from viewer.frame_input import poll_input

CTRL = ti.ui.CTRL


class FakeWindow:
    """One frame of GGUI's answers: the events queued since the last frame, in order (each gives its
    key only, as GGUI's binding does), and the keys down at the frame's end."""

    def __init__(self, events=(), down=()):
        self.events = [SimpleNamespace(key=k) for k in events]
        self.down = set(down)

    def get_events(self, tag=None):
        assert tag is None, "poll_input reads every kind of event, in order"
        return self.events

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


def test_a_chord_whose_key_comes_in_the_next_frame_is_still_a_chord():
    held, chord = frames(FakeWindow([CTRL], down=[CTRL]), FakeWindow(["s", "s", CTRL]))
    assert held.pressed == () and held.ctrl
    assert chord.pressed == ("ctrl+s",) and not chord.ctrl and chord.released == ("s", CTRL)


def test_a_key_typed_as_control_is_released_after_a_chord_is_plain():
    """ctrl+s, then p once Control is up: p (the viewer's screenshot), not ctrl+p, whether the
    events fall in two frames or in one (xdotool's `key ctrl+s p` often lands in one)."""
    chord, after = frames(FakeWindow([CTRL, "s"], down=[CTRL, "s"]), FakeWindow(["s", CTRL, "p", "p"]))
    assert chord.pressed == ("ctrl+s",) and chord.down == {CTRL, "s"}
    assert after.pressed == ("p",) and not after.ctrl and after.down == frozenset()
    (one,) = frames(FakeWindow([CTRL, "s", "s", CTRL, "p", "p"]))
    assert one.pressed == ("ctrl+s", "p")


def test_control_held_down_makes_every_key_a_chord():
    first, idle, second = frames(FakeWindow([CTRL, "z", "z"], down=[CTRL]), FakeWindow(down=[CTRL]),
                                 FakeWindow(["z", "z"], down=[CTRL]))
    assert (first.pressed, idle.pressed, second.pressed) == (("ctrl+z",), (), ("ctrl+z",))
    assert idle.down == {CTRL} and second.down == {CTRL}


def test_control_pressed_again_in_the_frame_it_is_released_starts_a_new_chord():
    """Released and pressed again within one frame, with a key: a new chord, whatever came before."""
    first, again = frames(FakeWindow([CTRL, "s"], down=[CTRL, "s"]),
                          FakeWindow(["s", CTRL, CTRL, "z", "z"], down=[CTRL]))
    assert first.pressed == ("ctrl+s",)
    assert again.pressed == ("ctrl+z",) and again.down == {CTRL}


def test_a_release_lost_with_the_focus_does_not_turn_the_next_press_into_a_release():
    """A key whose release never came (the window lost focus) is read as up from the window at the
    frame's end, so its next press is a press."""
    gone, back = frames(FakeWindow(["p"], down=[]), FakeWindow(["p"], down=["p"]))
    assert gone.pressed == ("p",) and gone.down == frozenset()
    assert back.pressed == ("p",)
