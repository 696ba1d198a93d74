"""pbrt's tokens with file and line; Include / Import, include loops and missing files
(renderer/scene/pbrt/tokenizer.py)."""
from __future__ import annotations

import gzip

import pytest

from renderer.scene.errors import SceneError
from renderer.scene.pbrt.tokenizer import TokenStream, tokenize

from tests.scene.pbrt.pbrt_helpers import CAMERA, SPHERE, load, write


def test_tokens_strings_numbers_brackets_comments_and_lines(tmp_path):
    tokens = tokenize('Shape "sphere" # a comment "not a token"\n  "float radius" [ 0.5 ]\n"a \\"q\\""', tmp_path)
    assert [(t.text, t.quoted, t.line) for t in tokens] == [
        ("Shape", False, 1), ("sphere", True, 1), ("float radius", True, 2), ("[", False, 2),
        ("0.5", False, 2), ("]", False, 2), ('a "q"', True, 3)]


def test_unterminated_string_is_one_line_naming_file_and_line(tmp_path):
    path = write(tmp_path, 'WorldBegin\nShape "sphere\n')
    with pytest.raises(SceneError) as e:
        TokenStream(path)
    assert str(e.value) == f"{path}: line 2: a string is not terminated on its line"


def test_include_and_import_relative_to_the_including_file(tmp_path):
    (tmp_path / "sub").mkdir()
    write(tmp_path, 'Import "more.pbrt"\n', "sub/part.pbrt")
    write(tmp_path, SPHERE, "sub/more.pbrt")
    scene, _ = load(tmp_path, 'Include "sub/part.pbrt"\nTranslate 1 0 0\n' + SPHERE)
    assert len(scene.mesh_objects) == 2
    assert {p.name for p in scene.source_files} == {"part.pbrt", "more.pbrt"}


def test_names_resolve_in_the_scenes_folder_first_as_pbrt_v4_does(tmp_path):
    (tmp_path / "geometry").mkdir()
    write(tmp_path, 'Include "geometry/ball.pbrt"\n', "geometry/part.pbrt")  # the top folder's name
    write(tmp_path, SPHERE, "geometry/ball.pbrt")
    scene, _ = load(tmp_path, 'Include "geometry/part.pbrt"\n')
    assert [o.kind for o in scene.mesh_objects] == ["sphere"]


def test_gzipped_include(tmp_path):
    (tmp_path / "part.pbrt.gz").write_bytes(gzip.compress(SPHERE.encode()))
    scene, _ = load(tmp_path, 'Include "part.pbrt.gz"\n')
    assert [o.kind for o in scene.mesh_objects] == ["sphere"]


def test_missing_include_is_one_line(tmp_path):
    with pytest.raises(SceneError) as e:
        load(tmp_path, 'Include "nowhere.pbrt"\n')
    message = str(e.value)
    assert "s.pbrt: line 5: cannot include 'nowhere.pbrt'" in message and "\n" not in message


def test_include_loop_names_the_chain(tmp_path):
    write(tmp_path, 'Include "b.pbrt"\n', "a.pbrt")
    write(tmp_path, 'Include "a.pbrt"\n', "b.pbrt")
    with pytest.raises(SceneError) as e:
        load(tmp_path, 'Include "a.pbrt"\n')
    assert "b.pbrt: line 1: include loop: a.pbrt -> b.pbrt -> a.pbrt" in str(e.value)


def test_unknown_directive_names_file_and_line(tmp_path):
    with pytest.raises(SceneError) as e:
        load(tmp_path, SPHERE + "Frobnicate 1 2 3\n")
    assert str(e.value) == f"{tmp_path / 's.pbrt'}: line 6: unknown directive 'Frobnicate'"
    assert CAMERA.count("\n") == 3  # the line numbers above count the camera's three lines
