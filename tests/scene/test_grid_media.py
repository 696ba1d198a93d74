"""Grid media in scene files (`[media.NAME] type = "grid"`, renderer/scene/grid_media.py): the box,
the albedo and the filter read into the grid specs, Features compile the grid code only where a
material or the fog names a grid medium, and bad fields are one line."""
import numpy as np
import pytest

from renderer.scene.errors import SceneError
from renderer.scene.features import scene_features
from renderer.scene.vol_files import write_vol
from tests.scene_builder import scene_from_toml

SCENE = """
[scene]
geometry = "sdf"
[media.smoke]
{medium}
[materials.boundary]
type = "null"
medium = "{used}"
[[objects]]
type = "box"
material = "boundary"
size = [1.0, 1.0, 1.0]
"""
GRID = 'type = "grid"\nfile = "d.vol"'


def load(tmp_path, medium: str, used: str = "smoke"):
    write_vol(tmp_path / "d.vol", np.arange(8, dtype=np.float32).reshape(2, 2, 2), bounds=((0, 0, 0), (2, 1, 1)))
    write_vol(tmp_path / "a.vol", np.full((1, 1, 1, 3), 0.5, np.float32))
    write_vol(tmp_path / "neg.vol", -np.ones((1, 1, 1), np.float32))
    return scene_from_toml(tmp_path, SCENE.format(medium=medium, used=used))


def test_a_grid_medium_reads_its_file_box_and_albedo(tmp_path):
    scene = load(tmp_path, GRID + '\nscale = 3.0\nbox_min = [-1.0, -1.0, -1.0]\nbox_max = [1.0, 0.0, 3.0]'
                                  '\nalbedo_file = "a.vol"\nfilter = "nearest"\ng = 0.2')
    (medium,) = scene.media
    assert (medium.kind, medium.scale, medium.g) == ("grid", 3.0, 0.2)
    assert medium.density.values.shape == (2, 2, 2, 1) and medium.density.values[1, 1, 1, 0] == 7.0
    np.testing.assert_allclose(medium.density.to_world, [[2, 0, 0, -1], [0, 1, 0, -1], [0, 0, 4, -1], [0, 0, 0, 1]])
    assert medium.albedo.to_world == medium.density.to_world and medium.albedo.file == tmp_path / "a.vol"
    assert medium.density.nearest and medium.albedo.nearest
    features = scene_features(scene)
    assert features.has_media and features.has_grid_media


def test_the_box_defaults_to_the_files_and_the_albedo_to_a_constant(tmp_path):
    (medium,) = load(tmp_path, GRID + "\nalbedo = [0.9, 0.8, 0.7]").media
    np.testing.assert_allclose(medium.density.to_world, [[2, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    assert medium.albedo.constant == pytest.approx((0.9, 0.8, 0.7)) and not medium.density.nearest


def test_grid_code_is_compiled_only_for_a_grid_medium_in_use(tmp_path):
    homogeneous = scene_features(load(tmp_path, "sigma_s = [1.0, 1.0, 1.0]"))
    assert homogeneous.has_media and not homogeneous.has_grid_media
    # Declared but named by no material: nothing of it is compiled.
    unused = load(tmp_path, GRID + "\n[media.air]\nsigma_s = [0.1, 0.1, 0.1]", used="air")
    assert not scene_features(unused).has_grid_media


@pytest.mark.parametrize("medium,problem", [
    ('type = "grid"', "media.smoke: missing required field 'file'"),
    ('type = "grid"\nfile = "d.raw"', "unsupported volume grid"),
    ('type = "grid"\nfile = "gone.vol"', "missing grid file gone.vol"),
    ('type = "grid"\nfile = "neg.vol"', "media.smoke.file: neg.vol holds negative densities"),
    (GRID + "\nbox_min = [0.0, 0.0, 0.0]", "media.smoke.box_max: box_min and box_max come together"),
    (GRID + "\nbox_min = [0.0, 0.0, 0.0]\nbox_max = [1.0, 0.0, 1.0]", "has no inside"),
    (GRID + "\nsigma_s = [1.0, 1.0, 1.0]", "sigma_s"),
    (GRID + "\nscale = -1.0", "media.smoke.scale"),
    ('file = "d.vol"', "file"),  # a homogeneous medium has no file
])
def test_bad_grid_media_are_one_line_errors(tmp_path, medium, problem):
    with pytest.raises(SceneError) as error:
        load(tmp_path, medium)
    text = str(error.value)
    assert problem in text and "\n" not in text
