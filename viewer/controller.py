"""Free-look (fly) camera controller: held keys move, mouse drags look around."""

from __future__ import annotations

import numpy as np

from viewer.camera_state import WORLD_UP, CameraState

MAX_DT = 0.25  # seconds; a longer stall must not teleport the camera
SHIFT_MULTIPLIER = 4.0
MIN_SPEED, MAX_SPEED = 0.01, 1000.0  # m/s
SPEED_STEP = 1.25
MOVEMENT_AXES = ("w", "s", "a", "d", "e", "q")  # the keys that move the camera (update: axis)


class FreeLookController:
    """Turns per-frame input into a new :class:`CameraState`.

    Keys (lower-case): w/s forward/back along the view direction, a/d left/right,
    q/e down/up along world y, shift = 4x speed. Dragging (any mouse button)
    rotates by ``look_sensitivity`` radians per pixel of cursor motion,
    independently of the frame time. ``cursor_px`` is in pixels with y growing
    downwards (screen convention): dragging right turns right, dragging up looks
    up. (A GGUI cursor, origin bottom-left in [0, 1], maps to ``(x * w, (1 - y) * h)``.)
    """

    def __init__(self, state: CameraState, move_speed: float = 2.0, look_sensitivity: float = 0.004):
        self._state = state
        self.move_speed = min(max(float(move_speed), MIN_SPEED), MAX_SPEED)
        self.look_sensitivity = float(look_sensitivity)
        self._last_cursor: tuple[float, float] | None = None

    @property
    def state(self) -> CameraState:
        return self._state

    def update(self, dt: float, held_keys: set[str], cursor_px: tuple[float, float] | None,
               dragging: bool) -> bool:
        """Advance one frame; returns True only if the camera actually changed."""
        dt = min(max(float(dt), 0.0), MAX_DT)
        keys = {k.lower() for k in held_keys}
        old = self._state
        position, yaw, pitch = np.array(old.position), old.yaw, old.pitch

        # Look: absolute cursor deltas, no dt, so rotation depends only on the mouse path.
        if dragging and cursor_px is not None:
            x, y = float(cursor_px[0]), float(cursor_px[1])
            if self._last_cursor is not None:  # the first update of a drag only records
                dx, dy = x - self._last_cursor[0], y - self._last_cursor[1]
                yaw -= dx * self.look_sensitivity
                pitch -= dy * self.look_sensitivity
            self._last_cursor = (x, y)
        else:
            self._last_cursor = None

        # Move: along the (new) view frame, speed * dt metres in total.
        moving = dt > 0.0 and any(k in keys for k in MOVEMENT_AXES)
        if not moving and yaw == old.yaw and pitch == old.pitch:
            return False  # a still frame: nothing to recompute
        forward, right, _ = old.replace(yaw=yaw, pitch=pitch).basis()
        axis = lambda pos, neg: int(pos in keys) - int(neg in keys)
        direction = axis("w", "s") * forward + axis("d", "a") * right + axis("e", "q") * WORLD_UP
        norm = np.linalg.norm(direction)
        if norm > 0.0 and dt > 0.0:
            speed = self.move_speed * (SHIFT_MULTIPLIER if "shift" in keys else 1.0)
            position = position + direction / norm * speed * dt

        self._state = old.replace(position=tuple(position), yaw=yaw, pitch=pitch)
        return self._state != old

    def change_speed(self, steps: int) -> None:
        """Scale move speed by 1.25**steps (clamped); not a camera change."""
        self.move_speed = min(max(self.move_speed * SPEED_STEP ** steps, MIN_SPEED), MAX_SPEED)

    def set_state(self, state: CameraState) -> bool:
        """Replace the state (focus, fov slider, scene switch...); True if it differed."""
        changed = state != self._state
        self._state = state
        return changed
