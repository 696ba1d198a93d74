"""A conductor's Fresnel descriptions in scene files: `base_color`/`edge_tint`, `eta`/`k` or a named
`metal`; exactly one of them, each refused elsewhere with a one-line error naming the file."""
import pytest

from renderer.scene.toml_loader import load_scene
from tests.scene.scene_file_helpers import load_error, scene_text, write


def conductor(body: str) -> str:
    return scene_text(materials='[materials.m]\ntype = "conductor"\n' + body)


def test_named_metal_and_complex_index_load(tmp_path):
    gold = load_scene(write(tmp_path, conductor('metal = "Au"\nroughness = 0.2\n'))).materials[0]
    assert gold.metal == "Au" and gold.eta is None and gold.has_complex_ior
    written = load_scene(write(tmp_path, conductor("eta = [0.2, 0.9, 1.1]\nk = [3.9, 2.4, 2.1]\n"))).materials[0]
    assert written.eta == (0.2, 0.9, 1.1) and written.k == (3.9, 2.4, 2.1) and written.has_complex_ior
    plain = load_scene(write(tmp_path, conductor("base_color = [0.9, 0.6, 0.5]\n"))).materials[0]
    assert not plain.has_complex_ior and plain.eta is None and plain.metal == ""


BAD = {
    "unknown metal lists the known ones": (conductor('metal = "Gold"\n'),
                                           "materials.m.metal: unknown value 'Gold' (allowed: a-C, Ag, Al,"),
    "metal with base_color": (conductor('metal = "Au"\nbase_color = [0.8, 0.8, 0.8]\n'),
                              "materials.m: `metal` and `base_color`/`edge_tint` cannot be combined"),
    "metal with eta and k": (conductor('metal = "Au"\neta = [1, 1, 1]\nk = [2, 2, 2]\n'),
                             "materials.m: `metal` and `eta`/`k` cannot be combined"),
    "eta and k with edge_tint": (conductor("eta = [1, 1, 1]\nk = [2, 2, 2]\nedge_tint = [1, 1, 1]\n"),
                                 "materials.m: `eta`/`k` and `base_color`/`edge_tint` cannot be combined"),
    "eta without k": (conductor("eta = [1, 1, 1]\n"), "materials.m: `eta` needs `k`"),
    "k without eta": (conductor("k = [1, 1, 1]\n"), "materials.m: `k` needs `eta`"),
    "negative k": (conductor("eta = [1, 1, 1]\nk = [2, -1, 2]\n"), "materials.m.k[1]: -1 is out of range"),
    "metal on a diffuse material": (scene_text(materials='[materials.m]\nmetal = "Au"\n'),
                                    "materials.m.metal: only allowed with type 'conductor' or 'coated', not 'diffuse'"),
    "eta on a dielectric": (scene_text(materials='[materials.m]\ntype = "dielectric"\neta = [1, 1, 1]\n'),
                            "materials.m.eta: only allowed with type 'conductor' or 'coated', not 'dielectric'"),
}


@pytest.mark.parametrize("text, expected", BAD.values(), ids=BAD.keys())
def test_bad_conductor_gives_one_line_error(tmp_path, text, expected):
    assert expected in load_error(write(tmp_path, text))
