"""scripts/view_scenes.py without a display: how it tells the viewer's "Please wait" box (shown
while kernels compile) in a screenshot of the window, and that it is placed by the window's origin."""
import numpy as np

from scripts.view_scenes import SIZE, WAIT_BAR, _waiting


def test_the_wait_box_is_found_by_its_title_bar_inside_the_window():
    screen = np.zeros((400, 640, 3), np.uint8)
    at = {"X": 80, "Y": 60}
    assert not _waiting(screen, at)
    screen[60 + 100, 80 + 90:80 + 390] = WAIT_BAR  # a title bar of 300 pixels in the window
    assert _waiting(screen, at)
    assert not _waiting(screen, {"X": 80, "Y": 60 + SIZE[1]})  # the same pixels outside that window
    screen[60 + 100, 80 + 90:80 + 150] = 0  # a bar of 240: still more than a third of the width
    assert _waiting(screen, at)
    screen[60 + 100, 80 + 90:80 + 300] = 0  # 90 pixels of that colour are the scene's, not the box
    assert not _waiting(screen, at)
