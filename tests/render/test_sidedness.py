"""Sidedness and coverage, rendered: a one-sided (Mitsuba) BSDF is black from behind and `twosided`
lights both sides; a back-face-culled material (glTF doubleSided: false) lets rays through from
behind (in a glTF file too, where a node's mirroring decides which side is the front) and still
shadows what its front faces; Mitsuba's `mask` lets a ray through with probability 1 - opacity (a
constant or a texture).

Each scene is a rectangle in front of a constant white environment, seen head-on; statistics are
z-tests at the 1% level per test (fixed seeds)."""
from __future__ import annotations

import numpy as np
from scipy import stats

from renderer.camera import CameraFrame
from renderer.materials.kinds import BACK_CULLED, TWO_SIDED
from renderer.materials.table import ALPHA_BLEND, MaterialRows
from renderer.renderer import Renderer
from renderer.scene.catalog import load_any
from renderer.scene.mesh_model import PbrMaterial
from tests.scene.model_file_helpers import write_quads_gltf

SIZE = 16
SPP = 64
INSIDE = (slice(5, 11), slice(5, 11))  # pixels that see the rectangle only
Z = stats.norm.isf(0.005)  # two-sided 1%


def render(scene, seed=1):
    renderer = Renderer(scene, (SIZE, SIZE))
    renderer.render(CameraFrame.from_spec(scene.camera), SPP, "mis", max_depth=scene.render.max_depth, seed=seed)
    return renderer.film.mean_image(), renderer.film.variance_of_mean_image()


def mitsuba_scene(tmp_path, name, bsdf, facing_away=False):
    turn = '<rotate y="1" angle="180"/>' if facing_away else ""
    path = tmp_path / f"{name}.xml"
    path.write_text(f'''<scene version="3.0.0"><integrator type="path"><integer name="max_depth" value="3"/></integrator>
        <sensor type="perspective"><float name="fov" value="30"/>
            <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
            <film type="hdrfilm"><rfilter type="box"/><integer name="width" value="{SIZE}"/>
            <integer name="height" value="{SIZE}"/></film></sensor>
        <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
        <shape type="rectangle"><transform name="to_world">{turn}</transform>{bsdf}</shape></scene>''')
    return load_any(path)


def test_a_one_sided_bsdf_is_black_from_behind_and_twosided_is_not(tmp_path):
    diffuse = '<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>'
    front, _ = render(mitsuba_scene(tmp_path, "front", diffuse))
    back, _ = render(mitsuba_scene(tmp_path, "back", diffuse, facing_away=True))
    both, _ = render(mitsuba_scene(tmp_path, "both", f'<bsdf type="twosided">{diffuse}</bsdf>', facing_away=True))
    assert front[INSIDE].min() > 0.3  # lit by the environment
    assert back[INSIDE].max() == 0.0  # exactly black: nothing scatters off the back face
    assert both[INSIDE].min() > 0.3
    assert front[0, 0].mean() == 1.0  # the corners see the environment


def test_a_mask_lets_through_one_minus_its_opacity(tmp_path):
    """A black two-sided rectangle under mask opacity 0.25: each pixel inside sees the white
    environment with probability 0.75."""
    black = '<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></bsdf>'
    mean, var = render(mitsuba_scene(tmp_path, "mask", f'<bsdf type="mask"><float name="opacity" value="0.25"/>'
                                                       f'{black}</bsdf>'), seed=3)
    inside, inside_var = mean[INSIDE][..., 1], var[INSIDE][..., 1]
    z = (inside.mean() - 0.75) / np.sqrt(inside_var.sum()) * inside.size
    assert abs(z) < Z, (inside.mean(), z)


def test_a_mask_texture_sets_the_opacity_where_it_is(tmp_path):
    """The opacity from a checkerboard (0 and 1): the opaque squares are black, the others the
    environment, exactly; the rectangle spans two by two squares."""
    black = '<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf></bsdf>'
    texture = ('<texture name="opacity" type="checkerboard"><rgb name="color0" value="0"/>'
               '<rgb name="color1" value="1"/></texture>')
    mean, _ = render(mitsuba_scene(tmp_path, "checker", f'<bsdf type="mask">{texture}{black}</bsdf>'))
    inside = mean[INSIDE][..., 1]
    # Away from the squares' edges (the middle row and column of pixels straddle them) every pixel is 0 or 1.
    corners = np.concatenate([inside[:2, :2].ravel(), inside[:2, -2:].ravel(), inside[-2:, :2].ravel(),
                              inside[-2:, -2:].ravel()])
    assert set(np.unique(corners)) == {0.0, 1.0} and (corners == 0.0).sum() == 8


def test_a_back_face_culled_surface_is_not_there_from_behind(tmp_path):
    def scene(culled, facing_away):
        path = tmp_path / f"cull_{culled}_{facing_away}.toml"
        rotate = "[180, 0, 0]" if facing_away else "[0, 0, 0]"
        path.write_text(f'''[scene]
name = "cull"
geometry = "mesh"
[camera]
position = [0, 5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
fov = 30
[render]
width = {SIZE}
height = {SIZE}
spp = {SPP}
[environment]
type = "constant"
color = [1, 1, 1]
[materials.card]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
sidedness = "{'back_culled' if culled else 'two_sided'}"
[[objects]]
type = "quad"
size = [2, 2]
rotate = {rotate}
material = "card"
''')
        return load_any(path)
    seen_through, _ = render(scene(True, True))
    assert (seen_through == 1.0).all()  # only the environment, through the culled back face
    front, _ = render(scene(True, False))
    assert front[INSIDE].max() < 0.9  # from the front it is there, a grey card
    kept, _ = render(scene(False, True))
    assert kept[INSIDE].max() < 0.9  # two-sided: there from behind too


def test_a_culled_face_still_shadows_what_its_front_faces(tmp_path):
    """A card facing down over a floor, seen from above: the camera sees the floor through its
    culled back, and that floor sees the card's front, which blocks the sky (paths are traced from
    the camera: renderer/geometry/coverage.py). Under the card's centre the floor gets about a fifth
    of the light the open floor gets, against all of it if the card let the sky through: the bound,
    0.4, is far from both (decided at the fixed seed, no test level)."""
    path = tmp_path / "shadow.toml"
    path.write_text(f'''[scene]
name = "shadow"
geometry = "mesh"
[camera]
position = [0, 5, 0]
look_at = [0, 0, 0]
up = [0, 0, -1]
fov = 30
[render]
width = {SIZE}
height = {SIZE}
[environment]
type = "constant"
color = [1, 1, 1]
[materials.floor]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
[materials.card]
type = "diffuse"
base_color = [0.5, 0.5, 0.5]
sidedness = "back_culled"
[[objects]]
type = "quad"
size = [8, 8]
material = "floor"
[[objects]]
type = "quad"
size = [1.2, 1.2]
rotate = [180, 0, 0]
translate = [0, 0.2, 0]
material = "card"
''')
    image, _ = render(load_any(path))
    under, open_floor = image[6:10, 6:10].mean(), image[[0, 0, -1, -1], [0, -1, 0, -1]].mean()
    assert under < 0.4 * open_floor


def test_a_mirrored_gltf_quad_is_culled_from_behind_its_turned_front(tmp_path):
    """A black single-sided glTF quad under a node mirrored through its plane (scale z = -1): its
    front, +z in the mesh, faces -z. From -z it is there; from +z the environment shows through.
    Without vertex normals, which would rewind it by themselves (renderer/scene/orientation.py)."""
    model = write_quads_gltf(tmp_path / "mirrored.gltf", [("mirrored", (0, 0, 0), (2, 2, -1), None, False, False)],
                             normals=False)

    def scene(z):
        path = tmp_path / f"mirrored_{z}.toml"
        path.write_text(f'''[scene]
name = "mirrored"
geometry = "mesh"
[camera]
position = [0, 0, {z}]
look_at = [0, 0, 0]
fov = 30
[render]
width = {SIZE}
height = {SIZE}
[environment]
type = "constant"
color = [1, 1, 1]
[[objects]]
type = "mesh"
file = "{model.name}"
''')
        return load_any(path)
    front, _ = render(scene(-5))
    assert front[INSIDE].max() < 0.5  # its black front (a little specular reflection)
    behind, _ = render(scene(5))
    assert (behind == 1.0).all()  # only the environment, through the culled back face


def test_gltf_single_sided_materials_are_culled_and_other_formats_are_not():
    rows = MaterialRows()
    single = rows.add_pbr(PbrMaterial(name="gltf", double_sided=False), lambda ref: -1)
    double = rows.add_pbr(PbrMaterial(name="obj"), lambda ref: -1)
    assert rows.rows[single]["sidedness"] == BACK_CULLED and rows.rows[double]["sidedness"] == TWO_SIDED
    assert rows.rows[single]["alpha_mode"] != ALPHA_BLEND  # culling is not coverage by alpha
