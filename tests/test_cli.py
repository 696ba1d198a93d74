"""The command line as a user meets it: one-line errors for bad input, list and info."""
import subprocess
import sys
from pathlib import Path

import pytest

import app
from renderer.renderer import Renderer
from renderer.scene import SceneError, load_scene
from tests.scene_builder import furnace_toml

ROOT = Path(__file__).resolve().parents[1]


def run_main(argv, capsys):
    code = app.main(argv)
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_line_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.startswith("error:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


def scene_file(tmp_path, body, name="s.toml"):
    path = tmp_path / name
    path.write_text(body)
    return str(path)


@pytest.mark.parametrize("mutate, expected", [
    (lambda b: b, None),  # control: the unmodified scene is valid
    (lambda b: b.replace('type = "sphere"', 'type = "sphre"'), "unknown primitive 'sphre'"),
    (lambda b: b.replace('material = "ball"', 'material = "balll"'), "unknown material 'balll'"),
    (lambda b: b.replace('radius = 0.5', 'radius = 0.5\nscale = [1.0, 2.0, 1.0]'), "non-uniform scale"),
    (lambda b: b.replace('type = "constant"\ncolor = [0.5, 0.5, 0.5]', 'type = "map"\nfile = "nope.exr"'), "nope.exr"),
    (lambda b: b.replace('[camera]', '[camera\n'), "s.toml"),
])
def test_bad_scene_gives_one_line_error_naming_file(tmp_path, capsys, mutate, expected):
    path = scene_file(tmp_path, mutate(furnace_toml()))
    if expected is None:
        assert load_scene(path).name == "s"
        return
    code, _, err = run_main(["render", path, "--spp", "1", "--out", str(tmp_path / "x.png")], capsys)
    line = one_line_error(err)
    assert code == 2 and path in line and expected in line


def test_missing_scene_file_and_unknown_name(tmp_path, capsys):
    code, _, err = run_main(["render", str(tmp_path / "missing.toml")], capsys)
    assert code == 2 and "missing.toml: file not found" in one_line_error(err)
    code, _, err = run_main(["info", "no_such_scene"], capsys)
    assert code == 2 and "no_such_scene" in one_line_error(err)


def test_unsupported_output_and_unknown_integrator(tmp_path, capsys):
    code, _, err = run_main(["render", "showcase", "--out", str(tmp_path / "a.jpg")], capsys)
    assert code == 2 and "'.jpg'" in one_line_error(err)
    code, _, err = run_main(["render", "showcase", "--integrator", "magic", "--out", str(tmp_path / "a.png")], capsys)
    assert code == 2 and "unknown integrator 'magic'" in one_line_error(err)


def test_corrupt_environment_map_is_a_scene_error(tmp_path):
    (tmp_path / "broken.exr").write_bytes(b"not an exr at all")
    body = furnace_toml().replace('type = "constant"\ncolor = [0.5, 0.5, 0.5]', 'type = "map"\nfile = "broken.exr"')
    scene = load_scene(scene_file(tmp_path, body))
    with pytest.raises(SceneError) as error:
        Renderer(scene)
    assert "broken.exr" in str(error.value) and "\n" not in str(error.value)


def test_list_and_info(capsys):
    code, out, _ = run_main(["list"], capsys)
    assert code == 0 and "showcase" in out and "path" in out and "steps" in out
    code, out, _ = run_main(["info", "showcase"], capsys)
    assert code == 0 and "has_dielectric" in out and "sdf_primitives" in out


def test_render_command_writes_png_and_exr(tmp_path):
    """A real subprocess, as a user runs it (its own Taichi runtime)."""
    for name in ("a.png", "a.exr"):
        out = tmp_path / name
        # The normals view: this checks the command and its files, and compiles in seconds.
        proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "showcase", "--spp", "2",
                               "--size", "32x18", "--out", str(out), "--arch", "cpu", "--integrator", "normals"],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        assert out.exists() and out.stat().st_size > 0
