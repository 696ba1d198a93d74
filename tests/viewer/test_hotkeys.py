from collections import Counter

from viewer.hotkeys import MOVEMENT_KEYS, KeyMap, build_hotkeys

NAMES = [f"integrator{i}" for i in range(12)]


def test_no_key_bound_twice():
    keys = Counter(h.key for h in build_hotkeys(NAMES))
    assert max(keys.values()) == 1


def test_action_keys_do_not_collide_with_movement_keys():
    movement = {h.key for h in MOVEMENT_KEYS}
    assert movement == {"w", "a", "s", "d", "q", "e", "shift"}
    assert not movement & {h.key for h in build_hotkeys(NAMES)}


def test_keys_are_lower_case_and_actions_set():
    for h in build_hotkeys(NAMES):
        assert h.key == h.key.lower() and h.action and h.description


def test_action_for():
    km = KeyMap(["path", "direct", "ao"])
    expected = {
        "n": "next_scene", "b": "prev_scene", "i": "next_integrator", "r": "reset",
        "p": "screenshot", "f": "focus_at_cursor", "h": "toggle_hud", "/": "help",
        "=": "speed_up", "+": "speed_up", "-": "speed_down", "escape": "quit",
        "Escape": "quit", "x": "toggle_denoise", "1": "integrator:path", "2": "integrator:direct", "3": "integrator:ao",
    }
    for key, action in expected.items():
        assert km.action_for(key) == action
    assert km.action_for("4") is None
    assert km.action_for("w") is None
    assert km.action_for("y") is None


def test_digits_cover_first_nine_integrators():
    actions = [h.action for h in build_hotkeys(NAMES) if h.key.isdigit()]
    assert actions == [f"integrator:{n}" for n in NAMES[:9]]


def test_help_text_lists_every_key():
    text = KeyMap(["path"]).help_text()
    lines = text.splitlines()
    for h in [*MOVEMENT_KEYS, *build_hotkeys(["path"])]:
        assert any(h.key in line.split("  ")[0].split() and h.description in line for line in lines), h
    assert "held" in text
