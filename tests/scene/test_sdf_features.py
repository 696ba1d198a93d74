"""What an SDF scene's description alone calls for (scene_features): its materials' effects are
compiled in as a mesh scene's would be."""
from __future__ import annotations

from renderer.scene import load_scene
from renderer.scene.features import scene_features
from tests.scene.scene_file_helpers import scene_text, write


def features_of(tmp_path, material: str):
    return scene_features(load_scene(write(tmp_path, scene_text(materials="[materials.m]\n" + material))))


def test_a_thin_dielectric_compiles_thin_walls(tmp_path):
    """Without has_thin a thin wall renders as thick glass (the BSDF ignores the row's flag)."""
    assert features_of(tmp_path, 'type = "dielectric"\nthin = true\n').has_thin
    assert not features_of(tmp_path, 'type = "dielectric"\n').has_thin


def test_one_sided_and_microfacet_models_compile_in(tmp_path):
    features = features_of(tmp_path, 'type = "conductor"\nroughness = 0.3\nmicrofacet = "beckmann"\n'
                                     'sidedness = "back_black"\n')
    assert features.has_microfacet_models and features.has_sidedness
    plain = features_of(tmp_path, 'type = "conductor"\nroughness = 0.3\n')
    assert not plain.has_microfacet_models and not plain.has_sidedness
