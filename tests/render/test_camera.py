"""Camera rays: pinhole and orthographic geometry and the thin lens's focus plane."""
import math

import numpy as np
import taichi as ti

from renderer.camera import CameraFrame, generate_ray
from renderer.sampling import dims
from renderer.sampling.sampler import IndependentSampler


def trace_camera(frame: CameraFrame, width, height, pixels, samples, dof):
    """(origins, directions), each (pixel, sample, 3), of the camera rays `frame` makes."""
    n = len(pixels) * samples
    origins = np.zeros((n, 3), np.float32)
    dirs = np.zeros((n, 3), np.float32)
    px = np.array(pixels, np.int32)

    sampler = IndependentSampler()

    @ti.kernel
    def kernel(px: ti.types.ndarray(), o: ti.types.ndarray(), d: ti.types.ndarray(),
               origin: ti.math.vec3, forward: ti.math.vec3, right: ti.math.vec3, up: ti.math.vec3,
               half_height: ti.f32, aperture: ti.f32, focus: ti.f32):
        for i in range(n):
            p = i // samples
            state = sampler.start(p, i % samples, 3)
            jitter = sampler.get2d(state, dims.PIXEL)  # the box filter's jitter, as the renderer draws it
            ray = generate_ray(px[p, 0], px[p, 1], width, height, jitter, sampler, state, origin, forward, right,
                               up, half_height, aperture, focus, dof, ti.static(frame.orthographic))
            for c in ti.static(range(3)):
                o[i, c] = ray.o[c]
                d[i, c] = ray.d[c]

    kernel(px, origins, dirs, *frame.kernel_args())
    return origins.reshape(len(pixels), samples, 3), dirs.reshape(len(pixels), samples, 3)


def test_pinhole_rays_span_the_field_of_view():
    frame = CameraFrame.look_at((1.0, 2.0, 3.0), (1.0, 2.0, 0.0), fov=60.0)
    o, d = trace_camera(frame, 64, 32, [(0, 0), (63, 31), (32, 16)], 64, False)
    assert np.allclose(o, [1.0, 2.0, 3.0])
    assert np.allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-6)
    # On the image plane at distance 1 the image spans +-tan(fov/2) vertically; the bottom pixel
    # row covers the lowest 1/16 of that span (2 of 32 half-rows).
    tan_half = math.tan(math.radians(30.0))
    plane_y = d[0, :, 1] / -d[0, :, 2]
    assert np.all(plane_y >= -tan_half - 1e-5) and np.all(plane_y <= -tan_half * (1 - 2 / 32) + 1e-5)
    assert np.all(d[0, :, 0] < 0) and np.all(d[1, :, 0] > 0)


def test_thin_lens_rays_of_a_pixel_meet_on_the_focus_plane():
    focus = 4.0
    frame = CameraFrame.look_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), fov=40.0, aperture=0.2, focus_distance=focus)
    o, d = trace_camera(frame, 32, 32, [(16, 16), (3, 28)], 256, True)
    # Lens points spread over the aperture disc...
    radius = np.linalg.norm(o[..., :2], axis=-1)
    assert radius.max() <= 0.2 + 1e-6 and radius.max() > 0.15
    # ...yet every ray of a pixel crosses the plane z = -focus within that pixel's footprint.
    t = (-focus - o[..., 2]) / d[..., 2]
    hits = o + t[..., None] * d
    footprint = 2 * focus * math.tan(math.radians(20.0)) / 32
    spread = np.ptp(hits[..., :2], axis=1).max()
    assert spread <= footprint * 1.01, (spread, footprint)


def test_orthographic_rays_are_parallel_and_leave_the_view_plane():
    frame = CameraFrame.look_at((1.0, 2.0, 3.0), (1.0, 2.0, 0.0), projection="orthographic", ortho_height=4.0)
    o, d = trace_camera(frame, 64, 32, [(0, 0), (63, 31), (32, 16)], 64, False)
    assert np.allclose(d, [0.0, 0.0, -1.0])
    assert np.allclose(o[..., 2], 3.0)
    # The view is 4 m tall and (64 / 32) * 4 m wide, centred on the eye; the bottom-left pixel covers
    # the first 1/64 of its width and 1/32 of its height.
    x, y = o[0, :, 0] - 1.0, o[0, :, 1] - 2.0
    assert np.all((x >= -4.0 - 1e-5) & (x <= -4.0 + 8.0 / 64 + 1e-5))
    assert np.all((y >= -2.0 - 1e-5) & (y <= -2.0 + 4.0 / 32 + 1e-5))
    assert np.all(o[1, :, 0] - 1.0 >= 4.0 - 8.0 / 64 - 1e-5) and np.all(o[1, :, 1] - 2.0 >= 2.0 - 4.0 / 32 - 1e-5)
    assert np.ptp(o[2, :, 0]) > 0.5 * 8.0 / 64  # jittered over the pixel, not a single point


def test_orthographic_lens_focuses_each_pixel_on_the_focus_plane():
    frame = CameraFrame.look_at((0.0, 0.0, 0.0), (0.0, 0.0, -1.0), aperture=0.2, focus_distance=3.0,
                                projection="orthographic", ortho_height=2.0)
    o, d = trace_camera(frame, 32, 32, [(16, 16), (3, 28)], 256, True)
    t = (-3.0 - o[..., 2]) / d[..., 2]
    hits = o + t[..., None] * d
    assert np.ptp(hits[..., :2], axis=1).max() <= 2.0 / 32 * 1.01  # within the pixel's footprint
    assert np.linalg.norm(o[..., :2] - hits[..., :2], axis=-1).max() > 0.15  # from all over the lens


def test_kernel_args_are_made_once_and_left_out_of_pickles_and_equality():
    import pickle

    frame = CameraFrame.look_at((1.0, 2.0, 3.0), (0.0, 0.0, 0.0), fov=50.0, aperture=0.1, focus_distance=2.5)
    args = frame.kernel_args()
    assert frame.kernel_args() is args  # a still view's frames reuse them
    copy = pickle.loads(pickle.dumps(frame))  # as a distributed worker receives a camera
    assert copy == frame and hash(copy) == hash(frame) and "_kernel_args" not in copy.__dict__
    again = copy.kernel_args()
    assert [list(a) if hasattr(a, "__len__") else a for a in again] == \
           [list(a) if hasattr(a, "__len__") else a for a in args]
