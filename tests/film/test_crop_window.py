"""Where a film lies on the camera's image (renderer/film/crop_window.py): a crop window's film is
its exact window of the image (rows counted up from the bottom, the crop's offset from the top); a
film of another size shows the window scaled to fit, centred; without a crop the film is the image."""
import pytest

from renderer.film.crop_window import FilmWindow, film_window


def test_a_film_of_the_crops_size_is_that_window_of_the_image():
    # 40x30 image, crop 10x6 at column 5, row 4 from the top: its bottom row is image row 30 - 4 - 6.
    assert film_window((5, 4, 10, 6), (40, 30), (10, 6)) == FilmWindow(40, 30, 5, 20)
    assert film_window((0, 0, 40, 30), (40, 30), (40, 30)) == FilmWindow(40, 30, 0, 0)
    assert film_window((30, 24, 10, 6), (40, 30), (10, 6)) == FilmWindow(40, 30, 30, 0)  # bottom-right corner


def test_without_a_crop_the_film_is_the_image_whatever_its_size():
    assert film_window(None, (40, 30), (64, 36)) == FilmWindow(64, 36, 0, 0)


def test_another_film_size_shows_the_crop_scaled_to_fit_and_centred():
    # Twice the crop's size: the image at twice its size, the window twice as far in.
    assert film_window((5, 4, 10, 6), (40, 30), (20, 12)) == FilmWindow(80, 60, 10, 40)
    # A wider film: the crop's height fills it (scale 2), the crop centred, the image continuing
    # beyond it on both sides (and here beyond the image's left edge).
    window = film_window((0, 4, 10, 6), (40, 30), (40, 12))
    assert (window.full_width, window.full_height) == (80, 60)
    assert window.x + 20 == 10 and window.y == 40  # the film's centre is the crop's centre


def test_film_points_map_to_the_image():
    window = FilmWindow(40, 30, 5, 20)
    assert window.image_uv(0.0, 0.0, 10, 6) == pytest.approx((5 / 40, 20 / 30))
    assert window.image_uv(1.0, 1.0, 10, 6) == pytest.approx((15 / 40, 26 / 30))
    assert FilmWindow(10, 6, 0, 0).image_uv(0.3, 0.7, 10, 6) == (0.3, 0.7)  # the whole image: as given
