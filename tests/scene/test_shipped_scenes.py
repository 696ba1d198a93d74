"""The scenes that ship in assets/scenes: each loads, mesh scenes name existing model files, and
the Cornell box is Mitsuba 3's `cornell_box()` value for value."""
from __future__ import annotations

import numpy as np
import pytest

from renderer.scene import CameraSpec, load_scene
from renderer.scene.description import MeshObject
from tests.scene.scene_file_helpers import REPO


SHIPPED = sorted((REPO / "assets" / "scenes").glob("*.toml"))
MESH_SCENES = ("cornell_box", "bunnies", "weekend", "textured", "stress", "many_lights", "studio", "pool", "goblet")


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_shipped_scene_loads(path):
    scene = load_scene(path)
    assert scene.geometry == ("mesh" if path.stem in MESH_SCENES else "sdf")
    if scene.geometry == "mesh":
        for obj in scene.mesh_objects:
            assert obj.file is None or obj.file.is_file()


def test_mesh_scenes_ship():
    assert set(MESH_SCENES) <= {p.stem for p in SHIPPED}


def test_cornell_box_matches_mitsuba_dictionary():
    """The values of Mitsuba 3's `mi.cornell_box()` (mitsuba/python/util.py)."""
    scene = load_scene(REPO / "assets" / "scenes" / "cornell_box.toml")
    assert (scene.render.width, scene.render.height, scene.render.spp, scene.render.max_depth) == (256, 256, 64, 8)
    assert scene.camera == CameraSpec(position=(0.0, 0.0, 3.9), look_at=(0.0, 0.0, 0.0), up=(0.0, 1.0, 0.0),
                                      fov=39.3077, aperture=0.0, focus_distance=scene.camera.focus_distance)
    assert (scene.environment.kind, scene.environment.color) == ("constant", (0.0, 0.0, 0.0))
    colours = {m.name: m.base_color for m in scene.materials}
    assert colours["white"] == (0.885809, 0.698859, 0.666422)
    assert colours["short_box"] == colours["tall_box"] == colours["white"]  # their own, for editing one
    assert colours["green"] == (0.105421, 0.37798, 0.076425)
    assert colours["red"] == (0.570068, 0.0430135, 0.0443706)
    assert all(m.kind == "diffuse" for m in scene.materials)
    emissive = [m for m in scene.materials if m.is_emissive]
    assert [m.emission for m in emissive] == [(18.387, 13.9873, 6.75357)]
    assert emissive[0].base_color == colours["white"]  # Mitsuba's light rectangle has the white BSDF
    assert all(o.kind == "quad" for o in scene.mesh_objects)
    assert len(scene.mesh_objects) == 5 + 1 + 2 * 6

    def corners(obj):
        hx, hz = obj.size[0] / 2, obj.size[1] / 2
        local = [(-hx, 0, -hz, 1), (hx, 0, -hz, 1), (hx, 0, hz, 1), (-hx, 0, hz, 1)]
        return [tuple(obj.matrix() @ c)[:3] for c in local]

    def normal(obj):
        return tuple(obj.matrix()[:3, :3] @ (0.0, 1.0, 0.0))

    # The room: five 2 x 2 quads on the faces of [-1, 1]^3 facing inwards, the light facing down.
    by_material = {}
    for obj in scene.mesh_objects:
        by_material.setdefault(obj.material, []).append(obj)
    light = by_material[emissive[0].name][0]
    xs, ys, zs = zip(*corners(light))
    assert (min(xs), max(xs), min(zs), max(zs)) == pytest.approx((-0.23, 0.23, -0.18, 0.20))
    assert ys == pytest.approx((0.99,) * 4)
    assert normal(light) == pytest.approx((0, -1, 0), abs=1e-12)
    (red,), (green,) = by_material["red"], by_material["green"]
    assert np.asarray(corners(red))[:, 0] == pytest.approx(-1.0) and normal(red) == pytest.approx((1, 0, 0), abs=1e-12)
    assert np.asarray(corners(green))[:, 0] == pytest.approx(1.0) and normal(green) == pytest.approx((-1, 0, 0), abs=1e-12)
    walls = [o for o in by_material["white"] if o.size == (2.0, 2.0)]
    assert sorted(tuple(np.round(normal(o), 9)) for o in walls) == sorted(
        [(0.0, 1.0, 0.0), (0.0, -1.0, 0.0), (0.0, 0.0, 1.0)])

    # The boxes: Mitsuba's unit cube [-1, 1]^3 under T(t) Ry(angle) S(s); each face of ours must
    # map to a face of that box, facing out.
    boxes = {"small": ((0.335, -0.7, 0.38), -17.0, (0.3, 0.3, 0.3)),
             "large": ((-0.33, -0.4, -0.28), 18.25, (0.3, 0.61, 0.3))}
    faces = by_material["short_box"] + by_material["tall_box"]
    assert len(faces) == 12 and not [o for o in by_material["white"] if o.size != (2.0, 2.0)]
    for name, (t, angle, s) in boxes.items():
        box = MeshObject("quad", translate=t, rotate=(0.0, angle, 0.0), scale=s).matrix()
        inverse = np.linalg.inv(box)
        mine = [o for o in faces if np.all(np.abs((inverse @ (*o.translate, 1.0))[:3]) <= 1 + 1e-6)]
        assert len(mine) == 6 and {o.material for o in mine} == {"short_box" if name == "small" else "tall_box"}, name
        seen = set()
        for obj in mine:
            local = np.array([inverse @ (*c, 1.0) for c in corners(obj)])[:, :3]
            axis = int(np.argmin(np.ptp(local, axis=0)))  # the coordinate all four corners share
            side = float(np.sign(local[0, axis]))
            assert local[:, axis] == pytest.approx(side, abs=1e-6), name
            others = [a for a in range(3) if a != axis]
            assert np.abs(local[:, others]) == pytest.approx(1.0, abs=1e-6), name  # the whole face
            n_local = box[:3, :3].T @ np.asarray(normal(obj))  # world -> local normal: M^T n
            assert np.sign(n_local[axis]) == side, name  # facing out
            seen.add((axis, side))
        assert len(seen) == 6, name
