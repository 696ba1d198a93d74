"""Input that cannot exhaust the machine: sizes a file declares are checked against the memory
budget before anything is allocated, references stay inside a model's folder, and every failure
is one line naming the file.

Each hostile input (tests/scene/hostile_inputs.py) is opened under tracemalloc: a refusal must
come before the allocation the file asks for, not after it.
"""
from __future__ import annotations

import io
import json
import os
import struct
import time
import tracemalloc
import warnings
from contextlib import redirect_stderr
from pathlib import Path

import numpy as np
import pytest

from renderer.scene import limits
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget, MemoryLedger, check_film, parse_size
from renderer.scene.load_options import LoadOptions
from renderer.scene.model_formats import load_mesh_asset
from tests.scene import hostile_inputs as h

MIB = 1 << 20
GIB = 1 << 30
SMALL = MemoryBudget(256 * MIB, "test budget")
# What a refusal may allocate on the way (parsing JSON, numpy scratch): far below what was asked.
REFUSAL_PEAK = 32 * MIB


def refused(call, *args, **kwargs) -> tuple[str, int, float]:
    """The one-line message of the SceneError `call` raises, the peak traced memory and seconds."""
    tracemalloc.start()
    start = time.perf_counter()
    try:
        with pytest.raises(SceneError) as error:
            call(*args, **kwargs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(error.value)
    assert "\n" not in message
    return message, peak, time.perf_counter() - start


def assert_budget_refusal(message: str, path) -> None:
    assert message.startswith(f"{path}: ")
    for part in ("needs", "more than the memory limit", "--memory-limit", "LANTERN_MEMORY_LIMIT"):
        assert part in message, message


def load(path, budget=SMALL, allow_outside=False):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return load_mesh_asset(path, LoadOptions(budget, allow_outside))


# --- the budget itself ---------------------------------------------------------------------------


@pytest.mark.parametrize("text, expected", [("8G", 8 * GIB), ("512M", 512 * MIB), ("2.5GiB", int(2.5 * GIB)),
                                            ("1000", 1000), ("1e9", 10 ** 9), (" 4k ", 4096), ("1T", 1 << 40)])
def test_sizes_parse(text, expected):
    assert parse_size(text) == expected


@pytest.mark.parametrize("text", ["", "lots", "-1G", "0", "8X", "G"])
def test_bad_sizes_are_refused(text):
    with pytest.raises(ValueError):
        parse_size(text)


def test_budget_comes_from_the_option_then_the_environment_then_the_memory():
    environ = {limits.ENVIRONMENT_VARIABLE: "2G"}
    assert MemoryBudget.from_settings("1G", environ).limit == GIB
    assert MemoryBudget.from_settings(None, environ).limit == 2 * GIB
    default = MemoryBudget.from_settings(None, {})
    assert default.limit == int(limits.physical_memory() * limits.DEFAULT_FRACTION)
    assert 0 < default.limit < limits.physical_memory()
    with pytest.raises(ValueError, match=limits.ENVIRONMENT_VARIABLE):
        MemoryBudget.from_settings(None, {limits.ENVIRONMENT_VARIABLE: "plenty"})
    with pytest.raises(ValueError, match="--memory-limit"):
        MemoryBudget.from_settings("plenty", {})


def test_the_ledger_adds_up_and_names_what_was_loaded():
    ledger = MemoryLedger(MemoryBudget(100, "test"))
    ledger.charge("f", "a", 60)
    ledger.check_peak("f", "passing", 40)  # fits beside what is booked, books nothing
    assert ledger.spent == 60 and ledger.high_water == 100
    with pytest.raises(SceneError, match="b needs 50 bytes on top of 60 bytes already loaded"):
        ledger.charge("f", "b", 50)


# --- glTF ----------------------------------------------------------------------------------------


def test_accessor_without_buffer_view_is_refused_before_allocating(tmp_path):
    """A 175-byte file declaring 400 million zero VEC3 positions: refused from the count."""
    path = h.huge_accessor_gltf(tmp_path, 400_000_000)
    assert path.stat().st_size < 500
    message, peak, seconds = refused(load, path, MemoryBudget(8 * GIB, "test"))
    assert_budget_refusal(message, path)
    assert peak < REFUSAL_PEAK and seconds < 5


def test_huge_sparse_accessor_is_refused(tmp_path):
    doc = {"asset": {"version": "2.0"},
           "accessors": [{"componentType": 5126, "count": 10 ** 9, "type": "VEC3",
                          "sparse": {"count": 1, "indices": {"bufferView": 0, "componentType": 5125},
                                     "values": {"bufferView": 1}}}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}]}
    path = h.write_json(tmp_path / "sparse.gltf", doc)
    message, peak, _ = refused(load, path)
    assert_budget_refusal(message, path)
    assert peak < REFUSAL_PEAK


def test_sparse_count_beyond_the_accessor_is_an_error(tmp_path):
    doc = h.triangle_gltf()
    doc["accessors"][0]["sparse"] = {"count": 4, "indices": {"bufferView": 0, "componentType": 5125},
                                     "values": {"bufferView": 0}}
    path = h.write_json(tmp_path / "sparse.gltf", doc)
    message, _, _ = refused(load, path)
    assert "sparse count 4 is larger than the accessor's 3" in message


def test_accessors_are_charged_together(tmp_path):
    """Two accessors that each fit the budget but not together: the second is refused."""
    doc = {"asset": {"version": "2.0"},
           "accessors": [{"componentType": 5126, "count": 6_000_000, "type": "VEC3"},
                         {"componentType": 5126, "count": 6_000_000, "type": "VEC3"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}}]}], "nodes": [{"mesh": 0}]}
    path = h.write_json(tmp_path / "two.gltf", doc)
    budget = MemoryBudget(200 * MIB, "test")  # one accessor: 144 MB decoded
    with pytest.raises(SceneError, match=r"accessors\[1\] .* on top of 137.3 MiB already loaded"):
        _load_accessors(path, budget)


def _load_accessors(path, budget):
    """Decode every accessor of a glTF through the loader's own reader (without the check of the
    mesh build, which would refuse this file first)."""
    from renderer.scene.model_formats.builder import AssetBuilder
    from renderer.scene.model_formats.gltf import GltfReader

    builder = AssetBuilder(path, Path(path), LoadOptions(budget), MemoryLedger(budget))
    reader = GltfReader(builder)
    reader.doc = json.loads(Path(path).read_text())
    for i in range(len(reader.doc["accessors"])):
        reader.accessor(i, "test")


def test_external_buffer_larger_than_the_budget_is_not_read(tmp_path):
    blob = tmp_path / "big.bin"
    blob.write_bytes(bytes(3 * MIB))
    doc = h.triangle_gltf(buffer_uri="big.bin")
    doc["buffers"][0]["byteLength"] = 60
    path = h.write_json(tmp_path / "buffer.gltf", doc)
    message, peak, _ = refused(load, path, MemoryBudget(2 * MIB, "test"))
    assert_budget_refusal(message, path)
    assert "buffers[0] (big.bin)" in message and peak < 2 * MIB


def test_a_node_with_two_parents_is_refused_before_placing_it_exponentially(tmp_path):
    """Forty nodes each listing the next twice would place the mesh 2^40 times."""
    nodes = [{"children": [i + 1, i + 1]} for i in range(40)] + [{"mesh": 0}]
    doc = h.triangle_gltf({"nodes": nodes, "scenes": [{"nodes": [0]}]})
    path = h.write_json(tmp_path / "dag.gltf", doc)
    message, _, seconds = refused(load, path)
    assert "nodes[40] is reached twice" in message and seconds < 5


def test_a_cycle_in_the_node_hierarchy_is_refused(tmp_path):
    doc = h.triangle_gltf({"nodes": [{"children": [1]}, {"children": [0], "mesh": 0}], "scenes": [{"nodes": [0]}]})
    path = h.write_json(tmp_path / "cycle.gltf", doc)
    message, _, _ = refused(load, path)
    assert "reached twice" in message and "cycle" in message


def test_a_byte_stride_shorter_than_an_element_is_refused(tmp_path):
    doc = h.triangle_gltf()
    doc["bufferViews"][0]["byteStride"] = 1
    path = h.write_json(tmp_path / "stride.gltf", doc)
    message, _, _ = refused(load, path)
    assert "byteStride 1 is shorter than one element (12 bytes)" in message


@pytest.mark.parametrize("count", [-1, 2.5, "3", True, 1e400])
def test_counts_that_are_not_counts_are_one_line_errors(tmp_path, count):
    doc = h.triangle_gltf()
    doc["accessors"][0]["count"] = count
    path = tmp_path / "count.gltf"
    path.write_text(json.dumps(doc).replace("Infinity", "1e400"))
    message, _, _ = refused(load, path)
    assert message.startswith(f"{path}: ")


# --- images --------------------------------------------------------------------------------------


def test_an_image_is_refused_from_its_header_before_decoding(tmp_path):
    """A PNG whose header claims 12000 x 12000 pixels (0.5 GiB of RGBA, kept three times)."""
    h.png_declaring(tmp_path / "huge.png", 12000, 12000)
    path = h.write_json(tmp_path / "textured.gltf", h.triangle_gltf(image_uri="huge.png"))
    message, peak, _ = refused(load, path, MemoryBudget(GIB, "test"))
    assert_budget_refusal(message, path)
    assert "image images[0] 'huge.png' (12000x12000)" in message
    assert peak < REFUSAL_PEAK


def test_a_real_12000_pixel_png_is_refused_without_decoding(tmp_path):
    path = h.huge_texture_gltf(tmp_path)
    assert (tmp_path / "huge.png").stat().st_size < 200_000
    message, peak, seconds = refused(load, path, MemoryBudget(GIB, "test"))
    assert_budget_refusal(message, path)
    assert peak < REFUSAL_PEAK and seconds < 5


def test_an_image_within_the_budget_still_decodes(tmp_path):
    from PIL import Image

    Image.new("RGB", (64, 32), (10, 20, 30)).save(tmp_path / "ok.png")
    asset = load(h.write_json(tmp_path / "ok.gltf", h.triangle_gltf(image_uri="ok.png")))
    assert asset.images[0].pixels.shape == (32, 64, 4)


# --- environment maps ----------------------------------------------------------------------------


def test_a_radiance_header_that_promises_more_than_the_file_holds(tmp_path):
    from renderer.output.image_io import read_environment

    path = h.huge_hdr(tmp_path / "huge.hdr")
    message, peak, _ = refused(read_environment, path, SMALL)
    assert message.startswith(f"{path}: cannot read Radiance HDR file (truncated: its header declares "
                              "100000x100000 pixels")
    assert peak < REFUSAL_PEAK


def test_a_radiance_map_over_the_budget_is_refused_before_decoding(tmp_path):
    from renderer.output.image_io import read_environment

    width, height = 2000, 1000
    path = tmp_path / "big.hdr"
    # enough bytes for run-length scanlines of this width, so only the budget can refuse it
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {height} +X {width}\n".encode()
                     + bytes(height * (4 + 8 * 16)))
    message, peak, _ = refused(read_environment, path, MemoryBudget(8 * MIB, "test"))
    assert_budget_refusal(message, path)
    assert "2000x1000 Radiance HDR map" in message and peak < REFUSAL_PEAK


def test_an_exr_header_over_the_budget_is_refused_before_decoding(tmp_path):
    from renderer.output.image_io import read_environment

    path = h.exr_declaring(tmp_path / "huge.exr", 100000, 100000)
    message, peak, _ = refused(read_environment, path, MemoryBudget(8 * GIB, "test"))
    assert_budget_refusal(message, path)
    assert "100000x100000 EXR" in message and peak < REFUSAL_PEAK


@pytest.mark.parametrize("resolution", [b"+Y 4 +X 4", b"-Y 4", b"-Y -4 +X 4", b"-Y 0 +X 4"])
def test_radiance_resolution_lines_we_cannot_read(tmp_path, resolution):
    from renderer.output.image_io import read_environment

    path = tmp_path / "odd.hdr"
    path.write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + resolution + b"\n" + bytes(256))
    message, _, _ = refused(read_environment, path, SMALL)
    assert message.startswith(f"{path}: ")


# --- the film ------------------------------------------------------------------------------------


def test_film_memory_is_refused_with_the_size_and_its_source():
    budget = MemoryBudget(11 * GIB, "test")
    with pytest.raises(SceneError) as error:
        check_film("scene.toml", 16384, 16384, budget, "--size")
    message = str(error.value)
    assert message.startswith("scene.toml: a 16384x16384 film (--size, ")
    assert f"{16384 * 16384 * limits.RENDER_BYTES_PER_PIXEL / GIB:.1f} GiB" in message
    check_film("scene.toml", 1920, 1080, budget, "--size")  # an ordinary film passes


def test_film_bytes_per_pixel_match_the_film_and_the_renderer(tmp_path):
    """The budget's count of the film's fields equals what a real Film allocates per pixel, and
    the renderer's work buffer is the 3 x f32 the budget assumes."""
    import taichi as ti

    from renderer.runtime.allocation import allocation_size
    from renderer.film.accumulation import Film
    from renderer.renderer import Renderer
    from renderer.scene.toml_loader import load_scene

    def cell_bytes(field) -> int:
        components = field.n * field.m if isinstance(field, ti.MatrixField) else 1
        return components * np.dtype(ti.lang.util.to_numpy_type(field.dtype)).itemsize

    width, height = 7, 5
    film = Film(width, height)
    per_pixel = [cell_bytes(v) for v in vars(film).values()
                 if isinstance(v, ti.Field) and tuple(v.shape) == (width, height)]
    assert len(per_pixel) == 5 and sum(per_pixel) == limits.FILM_FIELD_BYTES
    renderer = Renderer(load_scene(h.huge_film_scene(tmp_path, width, height)))
    # the renderer allocates whole steps (renderer/runtime/allocation.py), which the budget counts
    assert tuple(renderer.work.shape) == allocation_size(width, height) and cell_bytes(renderer.work) == 3 * 4
    assert tuple(renderer.film.mean.shape) == allocation_size(width, height)
    assert limits.RENDER_BYTES_PER_PIXEL == limits.FILM_FIELD_BYTES + 3 * 4 + 2 * 3 * 4
    from renderer.film.aovs import AovFilm

    aovs = AovFilm(width, height)
    aov_fields = [cell_bytes(v) for v in vars(aovs).values() if isinstance(v, ti.Field)]
    assert sum(aov_fields) + 2 * 3 * 4 == limits.AOV_BYTES_PER_PIXEL  # (+ the two images downloaded)


# --- references outside the model's folder -------------------------------------------------------


def test_a_texture_outside_the_models_folder_is_refused(tmp_path):
    path = h.escaping_uri_gltf(tmp_path)
    message, _, _ = refused(load, path)
    assert message == (f"{path}: images[0] '../outside.png' lies outside the model's folder "
                       f"{(tmp_path / 'model').resolve()} (--allow-outside-files reads it anyway)")
    asset = load(path, allow_outside=True)
    assert asset.images[0].pixels.shape == (2, 2, 4)


def test_absolute_paths_and_symlinks_leading_out_are_refused(tmp_path):
    from PIL import Image

    outside = tmp_path / "outside.png"
    Image.new("RGB", (2, 2)).save(outside)
    model = tmp_path / "model"
    model.mkdir()
    os.symlink(outside, model / "link.png")
    for uri in (str(outside), "link.png", "sub/../../outside.png"):
        path = h.write_json(model / "m.gltf", h.triangle_gltf(image_uri=uri))
        message, _, _ = refused(load, path)
        assert f"'{uri}' lies outside the model's folder" in message
    inside = model / "inside.png"
    Image.new("RGB", (2, 2)).save(inside)
    for uri in (str(inside), "./inside.png"):  # a path that stays inside is fine, absolute or not
        assert len(load(h.write_json(model / "m.gltf", h.triangle_gltf(image_uri=uri))).images) == 1


def test_buffers_outside_the_models_folder_are_refused(tmp_path):
    (tmp_path / "data.bin").write_bytes(bytes(60))
    (tmp_path / "model").mkdir()
    path = h.write_json(tmp_path / "model" / "m.gltf", h.triangle_gltf(buffer_uri="../data.bin"))
    message, _, _ = refused(load, path)
    assert "buffers[0] '../data.bin' lies outside the model's folder" in message


def test_obj_material_libraries_and_maps_outside_are_refused(tmp_path):
    from PIL import Image

    model = tmp_path / "model"
    model.mkdir()
    Image.new("RGB", (2, 2)).save(tmp_path / "outside.png")
    (tmp_path / "outside.mtl").write_text("newmtl a\nKd 1 0 0\n")
    obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n"
    (model / "lib.obj").write_text("mtllib ../outside.mtl\n" + obj)
    assert "material library '../outside.mtl' lies outside" in refused(load, model / "lib.obj")[0]
    (model / "inside.mtl").write_text("newmtl a\nmap_Kd ../outside.png\n")
    (model / "map.obj").write_text("mtllib inside.mtl\n" + obj)
    assert "material 'a' map_kd '../outside.png' lies outside" in refused(load, model / "map.obj")[0]


def test_a_ply_texture_file_outside_is_refused(tmp_path):
    from PIL import Image

    Image.new("RGB", (2, 2)).save(tmp_path / "outside.png")
    (tmp_path / "model").mkdir()
    ply = tmp_path / "model" / "t.ply"
    ply.write_text("ply\nformat ascii 1.0\ncomment TextureFile ../outside.png\nelement vertex 3\n"
                   "property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n"
                   "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                   "0 0 0 0 0\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n")
    assert "TextureFile '../outside.png' lies outside" in refused(load, ply)[0]


def test_scene_files_may_name_models_anywhere(tmp_path):
    """The folder rule is for a model's own references: a scene names what its author chose."""
    from renderer.scene.toml_loader import load_scene

    (tmp_path / "models").mkdir()
    h.write_json(tmp_path / "models" / "tri.gltf", h.triangle_gltf())
    (tmp_path / "scenes").mkdir()
    scene_path = tmp_path / "scenes" / "s.toml"
    scene_path.write_text(h.scene_text('[[objects]]\ntype = "mesh"\nfile = "../models/tri.gltf"\n', geometry="mesh"))
    scene = load_scene(scene_path)
    assert scene.model_files.load(scene.mesh_objects[0].file).triangle_count == 1


# --- symlink loops, truncated and damaged files -----------------------------------------------------


def test_symlink_loops_name_the_file(tmp_path):
    from renderer.scene.catalog import load_any, resolve_scene

    model = h.symlink_loop_model(tmp_path)
    assert str(refused(load, model)[0]) == f"{model}: symlink loop"
    assert str(refused(resolve_scene, str(model))[0]) == f"{model}: symlink loop"
    (tmp_path / "s").mkdir()
    scene = h.symlink_loop_scene(tmp_path / "s")
    message = refused(load_any, scene)[0]
    assert message == f"{scene}: objects[0]: model file loop_a.glb is a symlink loop"


def test_a_truncated_binary_stl_is_one_line(tmp_path):
    path = h.truncated_stl(tmp_path)
    message, _, _ = refused(load, path)
    assert message == (f"{path}: binary STL declares 12 triangles (684 bytes) but the file holds "
                       f"{path.stat().st_size} bytes (truncated or damaged)")


def test_text_stl_in_another_encoding_is_read(tmp_path):
    """trimesh decodes STL text that is not UTF-8 with charset_normalizer (a declared dependency)."""
    path = tmp_path / "latin.stl"
    path.write_bytes("solid caf\xe9\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                     "endloop\nendfacet\nendsolid caf\xe9\n".encode("latin-1"))
    assert load(path).triangle_count == 1


def test_any_failure_inside_a_reader_becomes_one_line(tmp_path, monkeypatch):
    """A library raising something unexpected still ends in one line naming the file."""
    import trimesh.exchange.ply

    def broken(*args, **kwargs):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(trimesh.exchange.ply, "load_ply", broken)
    path = tmp_path / "any.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 0\nend_header\n")
    assert refused(load, path)[0] == f"{path}: cannot read PLY file (ZeroDivisionError: float division by zero)"


# --- scene files ----------------------------------------------------------------------------------


def test_inline_tables_nested_beyond_the_parser_are_one_line(tmp_path):
    from renderer.scene.toml_loader import load_scene

    path = tmp_path / "deep.toml"
    path.write_text("a = " + "[" * 5000 + "]" * 5000 + "\n")
    message = refused(load_scene, path)[0]
    assert message == f"{path}: invalid TOML: arrays or inline tables nested too deeply to read"


def test_a_scene_file_too_large_to_parse_is_refused(tmp_path):
    from renderer.scene.toml_loader import TOML_PARSE_BYTES_PER_BYTE, load_scene

    path = tmp_path / "big.toml"
    path.write_text("# " + "x" * (2 * MIB) + "\n")
    message = refused(load_scene, path, LoadOptions(MemoryBudget(MIB * TOML_PARSE_BYTES_PER_BYTE, "test")))[0]
    assert_budget_refusal(message, path)


def test_operators_deeper_than_the_limit_are_refused(tmp_path):
    from renderer.scene import schema
    from renderer.scene.toml_loader import load_scene

    assert load_scene(h.deep_union_scene(tmp_path, schema.MAX_SDF_DEPTH - 1)).sdf_objects
    path = h.deep_union_scene(tmp_path, 400)
    # Refused by the loader's depth check (the message names the node), not by Python's recursion
    # limit or a compile: what the refusal costs in time is the parser's (no time bound here: the
    # suite's machine may be busy).
    message, _, _ = refused(load_scene, path)
    assert message.startswith(f"{path}: objects[0].children[1].children[1]")
    assert message.endswith(f": operators nest deeper than {schema.MAX_SDF_DEPTH} levels")


# --- the command line -------------------------------------------------------------------------------


def run_app(*argv) -> tuple[int, str, str]:
    import app

    out, err = io.StringIO(), io.StringIO()
    from contextlib import redirect_stdout

    with redirect_stdout(out), redirect_stderr(err), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = app.main(list(map(str, argv)))
    return code, out.getvalue(), err.getvalue()


def test_the_command_line_passes_the_limit_and_the_folder_rule(tmp_path):
    path = h.write_json(tmp_path / "tri.gltf", h.triangle_gltf())
    code, out, err = run_app("info", path, "--memory-limit", "1K")
    assert code == 2 and err.startswith(f"error: {path}: ") and "--memory-limit 1K" in err
    assert err.count("\n") == 1
    escaping = h.escaping_uri_gltf(tmp_path)
    code, out, err = run_app("info", escaping)
    assert code == 2 and "lies outside the model's folder" in err
    code, out, err = run_app("info", escaping, "--allow-outside-files")
    assert code == 0 and "escaping.gltf" in out
    code, _, err = run_app("info", path, "--memory-limit", "plenty")
    assert code == 2 and err == "error: --memory-limit: cannot read 'plenty' as a memory size (e.g. 8G, 512M, 2.5G)\n"


def test_the_render_command_refuses_a_film_over_the_budget(tmp_path):
    code, _, err = run_app("render", "showcase", "--size", "16384x16384", "--memory-limit", "4G",
                           "--out", tmp_path / "x.png")
    assert code == 2
    assert err.startswith("error: ") and "a 16384x16384 film (--size, " in err and err.count("\n") == 1


# --- the estimates bound what loading really takes ------------------------------------------------


def _big_gltf(folder: Path, vertices: int, attributes: tuple[str, ...], normal_map: bool) -> Path:
    """A random indexed mesh with the given attributes in an external buffer."""
    from PIL import Image

    rng = np.random.default_rng(1)
    widths = {"NORMAL": 3, "TEXCOORD_0": 2, "TEXCOORD_1": 2, "TANGENT": 4, "COLOR_0": 4}
    arrays = {"POSITION": rng.random((vertices, 3), dtype=np.float32)}
    arrays.update({k: rng.random((vertices, widths[k]), dtype=np.float32) for k in attributes})
    indices = rng.integers(0, vertices, 6 * vertices).astype(np.uint32)
    blobs = list(arrays.values()) + [indices]
    views, accessors, offset = [], [], 0
    for a in blobs:
        views.append({"buffer": 0, "byteOffset": offset, "byteLength": a.nbytes})
        kind = "SCALAR" if a.ndim == 1 else f"VEC{a.shape[1]}"
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125 if a.dtype == np.uint32 else 5126,
                          "count": len(a), "type": kind})
        offset += a.nbytes
    (folder / "big.bin").write_bytes(b"".join(a.tobytes() for a in blobs))
    material = {"pbrMetallicRoughness": {}}
    doc = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": offset, "uri": "big.bin"}],
           "bufferViews": views, "accessors": accessors, "materials": [material],
           "meshes": [{"primitives": [{"attributes": {k: i for i, k in enumerate(arrays)},
                                       "indices": len(blobs) - 1, "material": 0}]}],
           "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}]}
    if normal_map:
        Image.new("RGB", (4, 4), (128, 128, 255)).save(folder / "n.png")
        material["normalTexture"] = {"index": 0}
        doc.update(textures=[{"source": 0}], images=[{"uri": "n.png"}])
    return h.write_json(folder / "big.gltf", doc)


def _trimesh_export(folder: Path, name: str, **options) -> Path:
    import trimesh

    rng = np.random.default_rng(2)
    mesh = trimesh.Trimesh(rng.random((40_000, 3)), rng.integers(0, 40_000, (80_000, 3)), process=False)
    path = folder / name
    if name.endswith(".stl") and options.get("encoding") == "ascii":
        path.write_text(trimesh.exchange.stl.export_stl_ascii(mesh))
    else:
        mesh.export(path, **options)
    return path


def _image_gltf(folder: Path, name: str) -> Path:
    from PIL import Image

    rng = np.random.default_rng(3)
    size = (600, 400)
    if name.endswith("16.png"):
        import cv2

        cv2.imwrite(str(folder / name), (rng.random((size[1], size[0], 3)) * 65535).astype(np.uint16))
    elif name.endswith(".tiff"):
        Image.fromarray(rng.random((size[1], size[0])).astype(np.float32), "F").save(folder / name)
    else:
        Image.fromarray((rng.random((size[1], size[0], 3)) * 255).astype(np.uint8)).save(folder / name)
    return h.write_json(folder / "image.gltf", h.triangle_gltf(image_uri=name))


BUILDS = {
    "positions": lambda d: _big_gltf(d, 40_000, (), False),
    "every attribute, normal map": lambda d: _big_gltf(d, 40_000, ("NORMAL", "TEXCOORD_0", "TEXCOORD_1", "TANGENT",
                                                                  "COLOR_0"), True),
    "generated tangents": lambda d: _big_gltf(d, 40_000, ("NORMAL", "TEXCOORD_0"), True),
    "flat shading, normal map": lambda d: _big_gltf(d, 40_000, ("TEXCOORD_0",), True),
    "obj": lambda d: _trimesh_export(d, "m.obj"),
    "binary ply": lambda d: _trimesh_export(d, "m.ply"),
    "ascii ply": lambda d: _trimesh_export(d, "m.ply", encoding="ascii"),
    "binary stl": lambda d: _trimesh_export(d, "m.stl"),
    "ascii stl": lambda d: _trimesh_export(d, "m.stl", encoding="ascii"),
    "8-bit png": lambda d: _image_gltf(d, "rgb.png"),
    "16-bit png": lambda d: _image_gltf(d, "rgb16.png"),
    "float tiff": lambda d: _image_gltf(d, "grey.tiff"),
}


@pytest.mark.parametrize("name", BUILDS)
def test_estimates_bound_what_loading_takes(tmp_path, name):
    """The most a load was allowed to hold at once (the ledger's high-water mark) is at least the
    peak that tracemalloc sees numpy and Python allocate while loading."""
    import trimesh.exchange.load  # noqa: F401 - imported before measuring: its import is not the load's

    path = BUILDS[name](tmp_path)
    budget = MemoryBudget(64 * GIB, "test")
    ledger = MemoryLedger(budget)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tracemalloc.start()
        try:
            load_mesh_asset(path, LoadOptions(budget), ledger)
            peak = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    assert peak > 2 * MIB  # the case is big enough to measure
    assert peak <= ledger.high_water, f"peak {peak / MIB:.1f} MiB > estimate {ledger.high_water / MIB:.1f} MiB"
