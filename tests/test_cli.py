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


def test_render_writes_the_variance_of_each_pixel_mean(tmp_path):
    """`--out x.exr --variance x_var.exr` through the command line (a subprocess, as a user runs it).

    The files hold the film's mean and variance of the mean, bit for bit: the same scene, seed and
    sample count rendered here in-process give the same film (samples are hashes, independent of how
    the passes are split). And the variance is the right one for a z-test: with the mean and
    variance of a second render (another seed), z = (m1 - m2) / sqrt(v1 + v2) per pixel should be
    about N(0, 1), so sum(z^2) over the pixels (one channel: the scene is grey) is tested against
    chi-square with that many degrees of freedom, two-sided at alpha = 0.01. Pixels that see only the
    constant sky have variance 0 and must then agree exactly. Short paths (max depth 3) keep the
    per-pixel means close to normal at 64 spp."""
    import numpy as np
    from scipy import stats

    from renderer.camera import CameraFrame
    from renderer.image_io import read_exr

    path = scene_file(tmp_path, furnace_toml(env=0.8, albedo=0.6, max_depth=3))
    args = ["--spp", "64", "--size", "24x16", "--max-depth", "3", "--integrator", "path", "--arch", "cpu"]
    out, var = tmp_path / "a.exr", tmp_path / "a_var.exr"
    proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", path, *args, "--seed", "1",
                           "--out", str(out), "--variance", str(var)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    mean_file, variance_file = read_exr(out), read_exr(var)

    scene = load_scene(path)
    renderer = Renderer(scene, (24, 16))
    camera = CameraFrame.from_spec(scene.camera)
    films = []
    for seed in (1, 2):
        renderer.reset()
        renderer.render(camera, 64, "path", 3, seed)
        films.append((renderer.film.mean_image(), renderer.film.variance_of_mean_image()))
    np.testing.assert_array_equal(mean_file, films[0][0])
    np.testing.assert_array_equal(variance_file, films[0][1])
    assert np.isfinite(variance_file).all() and (variance_file >= 0).all()

    (m1, v1), (m2, v2) = ((m[..., 0].astype(np.float64), v[..., 0].astype(np.float64)) for m, v in films)
    constant = (v1 + v2) == 0.0
    np.testing.assert_array_equal(m1[constant], m2[constant])
    z = (m1 - m2)[~constant] / np.sqrt((v1 + v2)[~constant])
    dof = z.size
    assert dof > 100
    p_low, p_high = stats.chi2.cdf(np.sum(z * z), dof), stats.chi2.sf(np.sum(z * z), dof)
    assert min(p_low, p_high) >= 0.005, (np.sum(z * z), dof)


def test_variance_must_be_an_exr(tmp_path, capsys):
    code, _, err = run_main(["render", "showcase", "--out", str(tmp_path / "a.exr"),
                             "--variance", str(tmp_path / "v.png")], capsys)
    assert code == 2 and "v.png" in one_line_error(err) and "'.png'" in one_line_error(err)
