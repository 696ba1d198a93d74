"""The command line as a user meets it: one-line errors for bad input, list and info."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

import app
from renderer.renderer import Renderer
from renderer.scene import SceneError, load_scene
from tests.scene_builder import furnace_toml

ROOT = Path(__file__).resolve().parents[2]


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
    assert code == 0 and "'dielectric'" in out and "material_kinds" in out and "sdf_primitives" in out


def test_info_and_the_render_job_take_a_crop_window(tmp_path, capsys):
    from renderer.commands.headless import RenderJob

    body = furnace_toml().replace("width = 24\nheight = 16\n", "width = 24\nheight = 16\ncrop = [4, 2, 10, 8]\n")
    path = scene_file(tmp_path, body)
    code, out, _ = run_main(["info", path], capsys)
    assert code == 0 and "render:      24x16, cropped to 10x8 at (4, 2) from the top left" in out
    assert RenderJob().resolved(load_scene(path)).size == (10, 8)  # the image written is the window's


def test_render_command_writes_png_and_exr(tmp_path):
    """A real subprocess, as a user runs it (its own Taichi runtime), and what its files hold.

    The same scene, size, integrator, seed and sample count rendered here through the Renderer API
    give the same film bit for bit (samples are hashes of the seed and the sample index, whatever
    the passes), so the check is exact rather than statistical: the EXR holds that mean image, the
    PNG that image tone-mapped as the normals view maps it. A render of another scene, size, seed,
    sample count or camera, an image written upside down or with swapped channels, or a PNG tone
    mapped otherwise differs. The image is not blank either: the view shows several surfaces."""
    import imageio.v3 as iio
    import numpy as np

    from renderer.camera import CameraFrame
    from renderer.commands.headless import display_tonemapper
    from renderer.output.image_io import read_exr
    from renderer.output.tonemap import tonemap_array
    from renderer.scene.catalog import resolve_scene

    size, spp, seed = (32, 18), 2, 3
    for name in ("a.png", "a.exr"):
        out = tmp_path / name
        # The normals view: this checks the command and its files, and compiles in seconds.
        proc = subprocess.run([sys.executable, str(ROOT / "app.py"), "render", "showcase", "--spp", str(spp),
                               "--size", f"{size[0]}x{size[1]}", "--out", str(out), "--arch", "cpu",
                               "--integrator", "normals", "--seed", str(seed), "--optimize", "compile"],
                              capture_output=True, text=True, timeout=300)
        assert proc.returncode == 0, proc.stderr
        assert out.exists() and out.stat().st_size > 0

    scene = load_scene(resolve_scene("showcase"))
    renderer = Renderer(scene, size)
    renderer.render(CameraFrame.from_spec(scene.camera), spp, "normals", scene.render.max_depth, seed)
    expected = renderer.film.mean_image()
    assert expected.shape == (size[1], size[0], 3) and np.isfinite(expected).all()
    assert len(np.unique(expected.reshape(-1, 3), axis=0)) > 10  # many normals in view: not a blank image
    np.testing.assert_array_equal(read_exr(tmp_path / "a.exr"), expected)
    png = iio.imread(tmp_path / "a.png")
    assert png.shape == (size[1], size[0], 3) and png.dtype == np.uint8
    np.testing.assert_array_equal(png, tonemap_array(expected, 0.0, display_tonemapper("normals", None)))


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
    from renderer.output.image_io import read_exr

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


# --- checks before any rendering: output paths, numbers, checkpoints ------------------------------

@pytest.fixture
def no_rendering(monkeypatch):
    """Fails the test if the command gets as far as starting Taichi (everything below must be
    refused before that, so no kernel compiles)."""
    import renderer.runtime.arch

    def started(*args, **kwargs):
        raise AssertionError("Taichi was started: the input should have been refused before")

    monkeypatch.setattr(renderer.runtime.arch, "init_taichi", started)


@pytest.mark.parametrize("option, make, expected", [
    ("--out", lambda d: d / "folder.png", "is a directory"),
    ("--out", lambda d: d / "file.txt" / "a.png", "not a directory"),
    ("--out", lambda d: d / "file.txt" / "sub" / "a.png", "not a directory"),
    ("--out", lambda d: d / "a.tiff", "unsupported output extension '.tiff'"),
    ("--variance", lambda d: d / "file.txt" / "v.exr", "not a directory"),
    ("--variance", lambda d: d / "v.png", "unsupported variance extension"),
    ("--checkpoint", lambda d: d / "folder.ckpt", "is a directory"),
    ("--checkpoint", lambda d: d / "file.txt", "is not a Lantern checkpoint"),
    ("--checkpoint", lambda d: d / "file.txt" / "a.ckpt", "not a directory"),
])
def test_bad_output_paths_are_refused_before_rendering(tmp_path, capsys, no_rendering, option, make, expected):
    (tmp_path / "file.txt").write_text("a file, not a folder")
    (tmp_path / "folder.png").mkdir()
    (tmp_path / "folder.ckpt").mkdir()
    path = make(tmp_path)
    args = ["render", "showcase", "--out", str(tmp_path / "ok.png"), option, str(path)]
    code, _, err = run_main(args, capsys)
    line = one_line_error(err)
    assert code == 2 and str(path) in line and expected in line


def test_an_unwritable_output_folder_is_refused_before_rendering(tmp_path, capsys, no_rendering):
    """A folder no one may create files in, root included (CI runs the suite as root, who may write
    into any folder whatever its mode): /proc/sys, the root of the kernel's sysctl tree, refuses
    write access to everyone (Linux's proc_sys_permission)."""
    locked = Path("/proc/sys")
    assert locked.is_dir() and not os.access(locked, os.W_OK)
    out = locked / "lantern_test" / "a.png"
    code, _, err = run_main(["render", "showcase", "--out", str(out)], capsys)
    line = one_line_error(err)
    assert code == 2 and "permission denied" in line.lower() and str(out) in line


def test_the_same_file_for_two_outputs_is_refused(tmp_path, capsys, no_rendering):
    out = str(tmp_path / "a.exr")
    code, _, err = run_main(["render", "showcase", "--out", out, "--variance", out], capsys)
    assert code == 2 and "must be different files" in one_line_error(err)


@pytest.mark.parametrize("option, value, expected", [
    ("--time", "nan", "finite"), ("--time", "inf", "finite"), ("--time", "-1", "positive"), ("--time", "0", "positive"),
    ("--exposure", "nan", "finite"), ("--exposure", "inf", "finite"), ("--exposure", "-inf", "finite"),
    ("--exposure", "200", "within [-126, 127]"),
    ("--seed", "-1", ">= 0"), ("--seed", str(2**32), "at most 4294967295"), ("--seed", "1.5", "not an integer"),
    ("--spp", "0", ">= 1"), ("--spp", str(2**31), "at most 2147483647"), ("--spp", "many", "not an integer"),
    ("--max-depth", "0", "-1 or >= 1"), ("--max-depth", "-2", "-1 or >= 1"),
    ("--checkpoint-every", "0", "positive"), ("--checkpoint-every", "nan", "finite"),
    ("--size", "0x10", "out of range"),
])
def test_bad_numbers_are_one_line_errors_before_rendering(tmp_path, capsys, no_rendering, option, value, expected):
    # option=value: argparse takes a lone "-inf" for an option name
    code, _, err = run_main(["render", "showcase", f"{option}={value}", "--out", str(tmp_path / "a.png")], capsys)
    line = one_line_error(err)
    assert code == 2 and option in line and expected in line, line


def test_good_numbers_at_the_edges_of_their_ranges_are_accepted():
    parse = app.build_parser().parse_args
    args = parse(["render", "s", "--seed", str(2**32 - 1), "--spp", "1", "--max-depth", "-1", "--exposure", "-126"])
    assert (args.seed, args.spp, args.max_depth, args.exposure) == (2**32 - 1, 1, -1, -126.0)
    args = parse(["render", "s", "--time", "0.001", "--seed", "0", "--max-depth", "1"])
    assert (args.seconds, args.seed, args.max_depth) == (0.001, 0, 1)


def _checkpoint_for(tmp_path, **overrides):
    from renderer.output.checkpoint import save_checkpoint
    from tests.output.checkpoint_helpers import film_state, header_for

    scene = tmp_path / "s.toml"
    scene.write_text(furnace_toml(env=0.8, albedo=0.6, max_depth=3))
    path = tmp_path / "run.ckpt"
    save_checkpoint(path, header_for(scene, **overrides), film_state(24, 16, 2.0))
    return scene, path


@pytest.mark.parametrize("extra, expected", [
    (["OTHER"], "is not the checkpoint's"),
    (["--size", "32x16"], "size 32x16 differs from the checkpoint's 24x16"),
    (["--integrator", "nee"], "integrator nee differs from the checkpoint's path"),
    (["--seed", "9"], "seed 9 differs from the checkpoint's 0"),
    (["--max-depth", "5"], "max depth 5 differs from the checkpoint's 3"),
])
def test_a_foreign_checkpoint_is_refused(tmp_path, capsys, no_rendering, extra, expected):
    scene, path = _checkpoint_for(tmp_path)
    other = tmp_path / "other.toml"
    other.write_text(furnace_toml(env=0.3, albedo=0.6, max_depth=3))
    extra = [str(other) if a == "OTHER" else a for a in extra]
    code, _, err = run_main(["render", *extra, "--resume", str(path), "--out", str(tmp_path / "a.exr")], capsys)
    line = one_line_error(err)
    assert code == 2 and line.startswith(f"error: {path}: cannot continue") and expected in line, line


def test_a_checkpoint_of_another_version_or_a_changed_scene_is_refused(tmp_path, capsys, no_rendering):
    scene, path = _checkpoint_for(tmp_path, lantern_version="0.0.1")
    code, _, err = run_main(["render", "--resume", str(path)], capsys)
    assert code == 2 and "written by Lantern 0.0.1" in one_line_error(err)
    scene, path = _checkpoint_for(tmp_path)
    scene.write_text(scene.read_text().replace("fov = 50", "fov = 51"))
    code, _, err = run_main(["render", "--resume", str(path)], capsys)
    assert code == 2 and "has changed since the checkpoint" in one_line_error(err)


def test_resume_needs_a_target_beyond_the_checkpoint_and_a_film_integrator(tmp_path, capsys, no_rendering):
    scene, path = _checkpoint_for(tmp_path, spp_done=50)
    code, _, err = run_main(["render", "--resume", str(path), "--spp", "49"], capsys)
    assert code == 2 and "already has 50 spp" in one_line_error(err)
    code, _, err = run_main(["render", str(scene), "--integrator", "sppm", "--checkpoint", str(tmp_path / "p.ckpt")],
                            capsys)
    assert code == 2 and "sppm renders cannot be checkpointed" in one_line_error(err)
    code, _, err = run_main(["render", "--resume", str(tmp_path / "missing.ckpt")], capsys)
    assert code == 2 and "missing.ckpt: checkpoint not found" in one_line_error(err)
    code, _, err = run_main(["render"], capsys)
    assert code == 2 and "--resume" in one_line_error(err)


def test_the_scenes_exposure_is_the_default_and_the_option_overrides_it():
    from types import SimpleNamespace

    from renderer.commands.render_job import job_from_arguments
    from renderer.scene.description import RenderSettings

    scene = SimpleNamespace(render=RenderSettings(exposure=1.5))
    parse = app.build_parser().parse_args
    assert job_from_arguments(parse(["render", "s"]), scene, None).exposure == 1.5
    assert job_from_arguments(parse(["render", "s", "--exposure", "0"]), scene, None).exposure == 0.0


def test_the_packet_choices_are_the_packet_widths_and_zero():
    from renderer.packets.support import PACKET_WIDTHS

    assert app.PACKET_CHOICES == (0, *PACKET_WIDTHS)


def test_bench_flight_reaches_the_interactive_benchmark_and_only_it(capsys, monkeypatch):
    import renderer.bench.interactive as interactive

    calls = []
    monkeypatch.setattr(interactive, "run", lambda **options: calls.append(options) or 0)
    code, _, _ = run_main(["bench", "interactive", "--flight", "10", "--packets", "4"], capsys)
    assert code == 0 and calls[-1]["flight"] == 10.0 and calls[-1]["packets"] == 4
    code, _, err = run_main(["bench", "bvh", "--flight", "10"], capsys)
    assert code == 2 and "--flight is for bench interactive, not bvh" in one_line_error(err)
    with pytest.raises(SystemExit):
        app.build_parser().parse_args(["bench", "interactive", "--flight", "0"])
