"""The registry of material kinds and layers (renderer/materials/kinds.py) against what reads it:
the scene format, the device table, Features and the BSDF's dispatch."""
import dataclasses
import importlib

import pytest

from renderer.materials import kinds
from renderer.materials.kinds import COLUMNS, KIND_IDS, KIND_NAMES, KINDS, LAYER_NAMES, LAYERS, LobeFlags
from renderer.scene import schema
from renderer.scene.description import MATERIAL_KINDS, MaterialSpec
from renderer.scene.features import Features, features_from


def test_ids_are_positions_and_names_unique():
    assert MATERIAL_KINDS == KIND_NAMES == ("diffuse", "conductor", "dielectric", "principled", "null", "plastic", "disney",
                                                  "coated", "diffuse_transmission")
    assert [KIND_IDS[n] for n in KIND_NAMES] == list(range(len(KINDS)))
    assert len(set(LAYER_NAMES)) == len(LAYERS) and not set(LAYER_NAMES) & set(KIND_NAMES)
    assert all(layer.of in KIND_NAMES for layer in LAYERS)


def test_every_kind_has_a_lobe_module():
    for k in KINDS:
        module = importlib.import_module(k.lobes)
        for name in ("sample", "evaluate", "flags"):
            assert callable(getattr(module, name)), (k.name, name)


def test_flags_are_pbrt_bits():
    bits = (LobeFlags.REFLECTION, LobeFlags.TRANSMISSION, LobeFlags.DIFFUSE, LobeFlags.GLOSSY, LobeFlags.SPECULAR)
    assert sorted(bits) == [1, 2, 4, 8, 16]
    for entry in (*KINDS, *LAYERS):
        assert entry.flags and entry.flags & ~sum(bits) == 0, entry.name
    # What photon mapping and light sampling rely on: which kinds can be diffuse, and which refract.
    assert [k.name for k in KINDS if k.flags & LobeFlags.DIFFUSE] == ["diffuse", "principled", "plastic", "disney", "coated",
                                                                             "diffuse_transmission"]
    assert [k.name for k in KINDS if k.refracts] == ["dielectric", "principled", "disney"]
    assert kinds.kind("null").flags & LobeFlags.NON_DELTA == 0


def test_scene_format_fields_follow_the_registry():
    """Each material field belongs to the kinds whose own or layers' params name it; a param no
    field describes would be unreadable from scene files."""
    fields = {f.name: f for f in schema.MATERIAL.fields}
    for k in KINDS:
        for p in k.params:
            assert k.name in fields[p].only_for, (k.name, p)
    for layer in LAYERS:  # a layer's field belongs to its kind, and to kinds that name it as their own
        for p in layer.params:
            assert set(fields[p].only_for) == {layer.of} | {k.name for k in KINDS if p in k.params}, p
    assert fields["ior"].only_for == ("dielectric", "principled", "plastic", "disney", "coated")
    assert fields["microfacet"].only_for == ("conductor", "dielectric", "plastic")
    assert fields["edge_tint"].only_for == ("conductor",)
    assert fields["base_color"].only_for is None and fields["roughness"].only_for is None


def test_device_columns_once_each_with_spec_defaults():
    names = [c.name for c in COLUMNS]
    assert len(names) == len(set(names))
    spec = MaterialSpec("m")
    for c in COLUMNS:
        if c.from_spec:
            assert getattr(spec, c.name) == c.default, c.name  # a scene file's default is the table's
    for layer in LAYERS:
        assert all(c.name in names for c in layer.columns)


def test_table_rows_and_uses():
    from renderer.materials.table import MaterialRecord, MaterialRows

    assert list(MaterialRecord.members) == [c.name for c in COLUMNS]
    rows = MaterialRows()
    rows.add_spec(MaterialSpec("a", kind="conductor", roughness=0.3))
    rows.add_spec(MaterialSpec("b", kind="principled", sheen_color=(0.2, 0.1, 0.0)))
    rows.add_spec(MaterialSpec("c", kind="null", roughness=0.0))
    uses = rows.uses()
    assert uses["kinds"] == {"conductor", "principled", "null"} and uses["layers"] == {"sheen"}
    assert uses["rough"] is True
    arrays = rows.arrays()
    assert arrays["kind"].tolist() == [KIND_IDS["conductor"], KIND_IDS["principled"], KIND_IDS["null"]]
    smooth = MaterialRows()
    smooth.add_spec(MaterialSpec("a", kind="principled", roughness=0.5, specular=0.5, clearcoat=1.0))
    assert smooth.uses()["rough"] is False and smooth.uses()["layers"] == {"clearcoat", "specular"}


def test_every_material_row_is_its_place_in_the_scene_list_with_mixes_among_them():
    """Primitives name a material by its place in the scene's list: a mix's parts take rows after
    every material's (here a material after a mix, which took row 5 when parts followed their mix)."""
    from renderer.materials.table import MaterialRows

    a, b = MaterialSpec("a", kind="diffuse", base_color=(1, 0, 0)), MaterialSpec("b", kind="conductor")
    inner = MaterialSpec("inner", kind="diffuse", mix=(a, b))
    specs = [a, MaterialSpec("m", kind="diffuse", mix=(inner, b), mix_weight=0.25), MaterialSpec("c", kind="dielectric")]
    rows = MaterialRows()
    assert [rows.add_spec(s) for s in specs] == [0, 1, 2]
    arrays = rows.arrays()
    assert arrays["kind"][:3].tolist() == [KIND_IDS["diffuse"], KIND_IDS["diffuse"], KIND_IDS["dielectric"]]
    first, second = arrays["mix"][1][:2]
    assert first >= 3 and arrays["kind"][second] == KIND_IDS["conductor"] and arrays["mix"][first][0] >= 3
    assert arrays["base_color"][arrays["mix"][first][0]].tolist() == [1, 0, 0]  # the inner mix's first part


def test_features_hold_kind_and_layer_sets():
    uses = {"kinds": {"diffuse", "principled"}, "layers": {"clearcoat"}, "textures": False, "normal_maps": False,
            "emission": False, "rough": False}
    f = features_from("mesh", uses, "sky", 0.0)
    assert f.material_kinds == frozenset({"diffuse", "principled"}) and f.material_layers == frozenset({"clearcoat"})
    assert f.has_kind("principled") and not f.has_kind("dielectric") and f.has_layer("clearcoat")
    assert f.energy_compensation  # principled is always compensated
    assert not features_from("mesh", dict(uses, kinds={"conductor"}, layers=set()), "sky", 0.0).energy_compensation
    with pytest.raises(ValueError):
        features_from("mesh", dict(uses, kinds={"velvet"}), "sky", 0.0)
    every = Features().with_everything()
    assert every.material_kinds == frozenset(KIND_NAMES) and every.material_layers == frozenset(LAYER_NAMES)
    effects = f.optional_effects()
    assert "dielectric" in effects and "sheen" in effects and "principled" not in effects
    assert f.with_effect("sheen").material_layers == {"clearcoat", "sheen"}
    assert f.with_effect("null").has_kind("null") and f.with_effect("has_media").has_media
    bare = dataclasses.replace(f, material_kinds=frozenset(), energy_compensation=False)
    assert bare.active_effects() == ["clearcoat", "env:sky"]
    assert f.active_effects()[:2] == ["diffuse", "principled"]


@pytest.fixture(scope="module")
def every_kind_bench():
    from tests.materials.bsdf_kernels import BsdfBench

    features = Features(material_kinds=frozenset(KIND_NAMES), material_layers=frozenset(LAYER_NAMES),
                        energy_compensation=True, has_thin=True)
    return BsdfBench(capacity=16, features=features)


def test_flags_agree_with_has_smooth_part_and_the_registry(every_kind_bench):
    """Bsdf.flags (SPPM's question) and Bsdf.has_smooth_part (light sampling's) say the same of
    every kind and layer, and a material's flags are among its kind's and layers' registry flags."""
    import numpy as np
    import taichi as ti

    from tests.materials.bsdf_kernels import _surface

    @ti.kernel
    def ask(bsdf: ti.template(), ids: ti.types.ndarray(dtype=ti.i32, ndim=1),
            flags: ti.types.ndarray(dtype=ti.i32, ndim=1), smooth: ti.types.ndarray(dtype=ti.i32, ndim=1)):
        for i in range(ids.shape[0]):
            n = ti.math.vec3(0.0, 0.0, 1.0)
            mat, _ = bsdf.shade(_surface(ids[i], n), n)
            flags[i] = bsdf.flags(mat)
            smooth[i] = 1 if bsdf.has_smooth_part(mat) else 0

    specs = [MaterialSpec("d"), MaterialSpec("c0", kind="conductor", roughness=0.0),
             MaterialSpec("c1", kind="conductor", roughness=0.4), MaterialSpec("g0", kind="dielectric", roughness=0.0),
             MaterialSpec("g1", kind="dielectric", roughness=0.3),
             MaterialSpec("t", kind="dielectric", roughness=0.0, thin=True), MaterialSpec("n", kind="null"),
             MaterialSpec("p0", kind="principled", roughness=0.0, metallic=1.0),
             MaterialSpec("p1", kind="principled", roughness=0.0, metallic=0.0),
             MaterialSpec("p2", kind="principled", roughness=0.0, metallic=1.0, clearcoat=1.0,
                          clearcoat_roughness=0.5),
             MaterialSpec("p3", kind="principled", roughness=0.0, metallic=1.0, sheen_color=(0.5, 0.5, 0.5)),
             MaterialSpec("p4", kind="principled", roughness=0.0, transmission=1.0),
             MaterialSpec("p5", kind="principled", roughness=0.5, transmission=1.0)]
    ids = np.array([every_kind_bench.material(s) for s in specs], np.int32)
    flags = np.zeros(len(ids), np.int32)
    smooth = np.zeros(len(ids), np.int32)
    ask(every_kind_bench.bsdf, ids, flags, smooth)
    allowed = {k.name: k.flags for k in KINDS}
    for layer in LAYERS:
        allowed[layer.of] |= layer.flags
    for spec, f, s in zip(specs, flags, smooth):
        assert f and f & ~allowed[spec.kind] == 0, (spec.name, f)
        assert bool(f & LobeFlags.NON_DELTA) == bool(s), (spec.name, f, s)
    by_name = dict(zip((s.name for s in specs), flags))
    assert by_name["d"] & LobeFlags.DIFFUSE and not by_name["c1"] & LobeFlags.DIFFUSE
    assert by_name["c0"] & LobeFlags.SPECULAR and not by_name["c0"] & LobeFlags.NON_DELTA
    assert by_name["n"] == LobeFlags.TRANSMISSION | LobeFlags.SPECULAR
    assert by_name["p1"] & LobeFlags.DIFFUSE and not by_name["p0"] & LobeFlags.NON_DELTA
    assert by_name["p2"] & LobeFlags.GLOSSY and by_name["p3"] & LobeFlags.GLOSSY
    assert by_name["p4"] & LobeFlags.TRANSMISSION and not by_name["p4"] & LobeFlags.NON_DELTA
