"""Where a film lies on the camera's image: a crop window (Mitsuba's hdrfilm crop_offset_x,
crop_offset_y, crop_width, crop_height; a scene file's render.crop) renders only part of the image,
with the projection of the whole image. Plain Python: the Renderer passes the result to its kernels.

A kernel takes the film's pixel (x, y) to the image's (x + window.x, y + window.y) of a
full_width x full_height image: rays, the pixel filter's edges and the per-pixel random numbers are
the whole image's there, so a crop's pixels equal the same pixels of the whole render bit for bit
(rows run upwards, as the film's do: the crop's offset counts from the top, Mitsuba's way).

A film of the crop's own size (`render`) is that exact window. A film of another size (the viewer's
window, `render --size`) shows the crop window scaled to fit it, centred, the image around it
continuing beyond the crop (and beyond the image, as a viewer wider than the scene's aspect shows).
Without a crop the film is the whole image, whatever its size.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional


@dataclass(frozen=True)
class FilmWindow:
    full_width: int  # the image the projection spans, pixels
    full_height: int
    x: int  # the film's pixel (0, 0) (bottom-left) is the image's pixel (x, y), y up
    y: int

    @property
    def kernel_args(self) -> tuple[int, int, int, int]:
        return self.full_width, self.full_height, self.x, self.y

    def image_uv(self, u: float, v: float, width: int, height: int) -> tuple[float, float]:
        """The point (u, v) in [0, 1]^2 of a width x height film (y up) as the same fractions of the
        whole image."""
        if (self.full_width, self.full_height, self.x, self.y) == (width, height, 0, 0):
            return u, v  # the whole image: as given, without rounding
        return (self.x + u * width) / self.full_width, (self.y + v * height) / self.full_height


def whole_film(width: int, height: int) -> FilmWindow:
    return FilmWindow(width, height, 0, 0)


def film_window(crop: Optional[tuple[int, int, int, int]], image_size: tuple[int, int],
                film_size: tuple[int, int]) -> FilmWindow:
    """The window of a film of `film_size` onto an image of `image_size` cropped to `crop` ((x, y,
    width, height) from the image's top-left corner; None: no crop)."""
    width, height = film_size
    if crop is None:
        return whole_film(width, height)
    full_w, full_h = image_size
    cx, cy, cw, ch = crop
    if (width, height) == (cw, ch):
        return FilmWindow(full_w, full_h, cx, full_h - cy - ch)
    # Scaled so that the crop fits the film, centred on it. Rounding moves the view by under a pixel.
    s = min(width / cw, height / ch)
    centre_x, centre_y = (cx + 0.5 * cw) * s, (full_h - cy - 0.5 * ch) * s
    return FilmWindow(max(1, round(full_w * s)), max(1, round(full_h * s)), round(centre_x - 0.5 * width),
                      round(centre_y - 0.5 * height))
