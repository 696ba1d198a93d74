"""The viewer's key map as data. Action names are what the window loop dispatches on."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Hotkey:
    key: str  # lower-case key name as reported by GGUI ('escape', '/', 'a', ...)
    action: str | None  # None for held movement keys, which are polled, not dispatched
    description: str


MAX_INTEGRATOR_KEYS = 9  # digit keys '1'..'9'
# Taichi 1.7's window reports letters, Escape, Tab, Space, Return, BackSpace, arrows and
# modifiers only: digits and punctuation never arrive. Every action therefore has a key from that
# set; digits and punctuation stay as aliases for back-ends that do deliver them.

MOVEMENT_KEYS: tuple[Hotkey, ...] = (
    Hotkey("w", None, "move forward (held)"),
    Hotkey("s", None, "move back (held)"),
    Hotkey("a", None, "move left (held)"),
    Hotkey("d", None, "move right (held)"),
    Hotkey("q", None, "move down (held)"),
    Hotkey("e", None, "move up (held)"),
    Hotkey("shift", None, "move 4x faster (held)"),
)


def build_hotkeys(integrator_names: list[str], integrator_letters: dict[str, str] | None = None) -> list[Hotkey]:
    """Action hotkeys. Integrator k is selected by its letter (``integrator_letters[name]``) and by
    digit k (first nine only)."""
    keys = [
        Hotkey("n", "next_scene", "next scene"),
        Hotkey("b", "prev_scene", "previous scene"),
        Hotkey("i", "next_integrator", "next integrator"),
    ]
    letters = integrator_letters or {}
    for digit, name in enumerate(integrator_names, start=1):
        if name in letters:
            keys.append(Hotkey(letters[name], f"integrator:{name}", f"integrator: {name}"))
        if digit <= MAX_INTEGRATOR_KEYS:
            keys.append(Hotkey(str(digit), f"integrator:{name}", f"integrator: {name}"))
    keys += [
        Hotkey("r", "reset", "reset the accumulation"),
        Hotkey("p", "screenshot", "save screenshot"),
        Hotkey("x", "toggle_denoise", "toggle the denoised view (Open Image Denoise, when still)"),
        Hotkey("f", "focus_at_cursor", "focus at the cursor"),
        Hotkey("l", "pick_at_cursor", "pick what is under the cursor (or click it): its material panel"),
        Hotkey("h", "toggle_hud", "toggle HUD"),
        Hotkey("tab", "help", "toggle this help"),
        Hotkey("/", "help", "toggle this help"),
        Hotkey("f1", "help", "toggle this help"),
        Hotkey("up", "speed_up", "faster movement"),
        Hotkey("=", "speed_up", "faster movement"),
        Hotkey("+", "speed_up", "faster movement"),
        Hotkey("down", "speed_down", "slower movement"),
        Hotkey("-", "speed_down", "slower movement"),
        Hotkey("escape", "quit", "quit"),
    ]
    return keys


class KeyMap:
    """Lookup and help text for the key map built from ``integrator_names``."""

    def __init__(self, integrator_names: list[str] = (), integrator_letters: dict[str, str] | None = None):
        self.hotkeys = build_hotkeys(list(integrator_names), integrator_letters)
        self._actions = {h.key: h.action for h in self.hotkeys}
        if len(self._actions) != len(self.hotkeys):
            raise ValueError("a key is bound to more than one action")

    def action_for(self, key: str) -> str | None:
        """Action bound to ``key`` (case-insensitive), or None (movement / unbound)."""
        return self._actions.get(key.lower())

    def help_text(self) -> str:
        """One line per action, ``"keys  description"``, keys sharing an action merged."""
        rows: dict[tuple, list[str]] = {}
        for h in (*MOVEMENT_KEYS, *self.hotkeys):
            group = (h.action or h.key, h.description)
            rows.setdefault(group, []).append(h.key)
        lines = [(" ".join(keys), desc) for (_, desc), keys in rows.items()]
        lines += [("ctrl+z ctrl+y", "undo / redo a material edit"), ("ctrl+s", "save the edited scene beside its file")]
        width = max(len(k) for k, _ in lines)
        return "\n".join(f"{k:<{width}}  {desc}" for k, desc in lines)
