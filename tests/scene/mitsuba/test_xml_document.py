"""Mitsuba 3 scene files, the file layer: malformed XML, <default> and $name with -D, <include>
(and its loops), <path>, and the one-line errors a bad file gets."""
from __future__ import annotations

import pytest

from renderer.scene.errors import SceneError
from renderer.scene.load_options import LoadOptions, parse_defines
from renderer.scene.mitsuba import load_mitsuba_scene
from renderer.scene.mitsuba.xml_document import Resolution, resolve_document

SPHERE = '<shape type="sphere"><float name="radius" value="{radius}"/></shape>'


def write(folder, name, text):
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return path


def scene_text(body: str) -> str:
    return f'<scene version="3.0.0">\n{body}\n</scene>\n'


def load(path, **defines):
    return load_mitsuba_scene(path, LoadOptions(defines=tuple(defines.items())))


def test_malformed_xml_names_line_and_column(tmp_path):
    path = write(tmp_path, "bad.xml", '<scene version="3.0.0">\n  <shape type="sphere">\n</scene>\n')
    with pytest.raises(SceneError) as error:
        load(path)
    text = str(error.value)
    assert text.startswith(str(path)) and "line 3, column 3" in text and "malformed XML" in text
    assert "\n" not in text


def test_default_and_define(tmp_path):
    path = write(tmp_path, "s.xml", scene_text('<default name="r" value="2"/>' + SPHERE.format(radius="$r")))
    assert load(path).mesh_objects[0].radius == 2.0
    assert load(path, r="0.5").mesh_objects[0].radius == 0.5  # -D wins over <default>


def test_a_name_without_a_value_is_one_line(tmp_path):
    path = write(tmp_path, "s.xml", scene_text(SPHERE.format(radius="$radius")))
    with pytest.raises(SceneError, match=r"line 2: \$radius has no value: give it with -D radius=VALUE"):
        load(path)


def test_include_splices_the_file_in_and_paths_are_searched(tmp_path):
    write(tmp_path, "parts/ball.xml", scene_text(SPHERE.format(radius="3")))
    write(tmp_path, "lib/mesh.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    main = write(tmp_path, "scene/main.xml", scene_text(
        '<path value="../lib"/><include filename="../parts/ball.xml"/>'
        '<shape type="obj"><string name="filename" value="mesh.obj"/></shape>'))
    scene = load(main)
    assert [o.kind for o in scene.mesh_objects] == ["sphere", "mesh"]
    assert scene.mesh_objects[0].radius == 3.0
    assert scene.mesh_objects[1].file == tmp_path / "scene" / "../lib" / "mesh.obj"


def test_include_loop_is_one_line(tmp_path):
    write(tmp_path, "a.xml", scene_text('<include filename="b.xml"/>'))
    write(tmp_path, "b.xml", scene_text('<include filename="a.xml"/>'))
    with pytest.raises(SceneError, match=r"b.xml: line 2: <include> loop: a.xml -> b.xml -> a.xml"):
        load(tmp_path / "a.xml")


def test_missing_include_and_missing_mesh_name_the_file(tmp_path):
    path = write(tmp_path, "s.xml", scene_text('<include filename="nowhere.xml"/>'))
    with pytest.raises(SceneError, match=r"line 2: <include>: file not found"):
        load(path)
    path = write(tmp_path, "t.xml", scene_text('<shape type="ply"><string name="filename" value="gone.ply"/></shape>'))
    with pytest.raises(SceneError, match=r"t.xml: line 2: <shape type=\"ply\">: gone.ply: file not found"):
        load(path)


def test_root_must_be_a_scene(tmp_path):
    path = write(tmp_path, "s.xml", "<shape type='sphere'/>")
    with pytest.raises(SceneError, match="the root element is <shape>, not <scene>"):
        resolve_document(path, Resolution({}, [tmp_path], [path]))


@pytest.mark.parametrize("items, problem", [(["a=1", "b=x=y"], None), (["novalue"], "expected NAME=VALUE"),
                                            (["=3"], "expected NAME=VALUE"), (["a b=2"], "expected NAME=VALUE")])
def test_define_arguments(items, problem):
    if problem is None:
        assert parse_defines(items) == (("a", "1"), ("b", "x=y"))
    else:
        with pytest.raises(ValueError, match=problem):
            parse_defines(items)


def test_the_files_read_are_what_checkpoints_and_bundles_cover(tmp_path):
    from renderer.output.checkpoint import scene_files

    write(tmp_path, "parts/ball.xml", scene_text(SPHERE.format(radius="1")))
    write(tmp_path, "eta.spd", "400 1.5\n700 1.6\n")
    write(tmp_path, "wood.png", "")
    main = write(tmp_path, "main.xml", scene_text(
        '<include filename="parts/ball.xml"/><shape type="sphere"><bsdf type="conductor">'
        '<spectrum name="eta" filename="eta.spd"/><spectrum name="k" value="2"/></bsdf></shape>'
        '<shape type="sphere"><bsdf type="diffuse"><texture name="reflectance" type="bitmap">'
        '<string name="filename" value="wood.png"/></texture></bsdf></shape>'))
    scene = load(main)
    assert {p.name for p in scene_files(scene)} == {"main.xml", "ball.xml", "eta.spd", "wood.png"}


def test_other_parameters_are_another_scene_to_a_checkpoint(tmp_path):
    """-D changes the scene: a checkpoint of one rendering refuses to continue as the other."""
    from renderer.output.checkpoint import scene_fingerprint

    path = write(tmp_path, "s.xml", scene_text('<default name="r" value="2"/>' + SPHERE.format(radius="$r")))
    assert scene_fingerprint(load(path)) == scene_fingerprint(load(path))
    assert scene_fingerprint(load(path, r="3")) != scene_fingerprint(load(path))
    assert load(path, r="3").parameters == (("r", "3"),)
