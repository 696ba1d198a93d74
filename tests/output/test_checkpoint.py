"""Checkpoints: the film's exact state round-trips, a continued render is bit for bit the render that
never stopped, and damaged or foreign checkpoints are refused in one line."""
import numpy as np
import pytest

from renderer.output.checkpoint import load_checkpoint, read_header, save_checkpoint, scene_fingerprint, scene_files
from renderer.film.accumulation import FilmState
from renderer.commands.headless import RenderJob, Resume, pass_slices, render
from renderer.film.pixel_slices import ROUND_SLICES
from renderer.scene import SceneError, load_scene
from tests.output.checkpoint_helpers import film_state, header_for
from tests.scene_builder import furnace_toml

ARRAYS = [name for name, _, _ in FilmState.ARRAYS]


@pytest.fixture
def scene_path(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text(furnace_toml(env=0.8, albedo=0.6, max_depth=3))
    return path


def assert_same_state(a: FilmState, b: FilmState):
    for name in ARRAYS:
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        np.testing.assert_array_equal(x, y, err_msg=name)  # NaN == NaN; float32 bit patterns of finite values


class StopAfter:
    """A stop request after `passes` render passes (what a signal does, without the signal)."""

    def __init__(self, passes: int):
        self.passes = passes
        self.asked = 0

    def defer(self):
        pass

    @property
    def requested(self) -> bool:
        self.asked += 1
        return self.asked > self.passes


def test_checkpoint_round_trip_is_exact(tmp_path, scene_path):
    rng = np.random.default_rng(3)
    state = FilmState(rng.normal(size=(16, 24, 3)).astype(np.float32),
                      rng.exponential(size=(16, 24, 3)).astype(np.float32),
                      rng.integers(0, 1000, size=(16, 24), dtype=np.int32),
                      rng.integers(0, 3, size=(16, 24), dtype=np.int32))
    state.m2[0, 0] = np.inf  # sppm-like unknown variance survives too
    header = header_for(scene_path, spp_done=123, seconds_budget=None)
    save_checkpoint(tmp_path / "a.ckpt", header, state)
    loaded_header, loaded = load_checkpoint(tmp_path / "a.ckpt")
    assert loaded_header == header == read_header(tmp_path / "a.ckpt")
    assert_same_state(loaded, state)


@pytest.mark.parametrize("passes", [3, 7])
def test_continuing_a_stopped_render_is_bit_identical(scene_path, passes):
    """Stopped after a few passes, saved, restored into a new Renderer and continued to 300 spp: the
    same film (mean, m2, counts, rejected) and image as 300 spp in one go, with another pass split.
    Three passes (1 + 4 + 16 pixel slices) stop within the first sample's round; seven, after it."""
    scene = load_scene(scene_path)
    job = RenderJob(spp=300, size=(24, 16), integrator="path", seed=11)
    whole = render(scene, job)
    part = render(scene, job, stop=StopAfter(passes))
    assert part.interrupted and 0 < part.mean_spp < 300 and (part.spp == 0) == (passes == 3)
    state = part.film.state()
    continued = render(scene, job, resume=Resume(state, part.spp, part.seconds_rendered, part.slices_in_round))
    assert continued.spp == whole.spp == 300 and not continued.interrupted
    assert_same_state(continued.film.state(), whole.film.state())
    np.testing.assert_array_equal(continued.image, whole.image)
    np.testing.assert_array_equal(continued.variance, whole.variance)


def test_a_render_stopped_within_its_first_sample_is_an_image(scene_path):
    """One pass (one pixel slice of 256) of a furnace where every pixel is lit: the image is whole,
    finite and non-zero everywhere (unreached pixels filled from the sampled grid), while only the
    reached pixels have a finite variance and a sample."""
    scene = load_scene(scene_path)
    part = render(scene, RenderJob(spp=300, size=(40, 24), integrator="path", seed=2), stop=StopAfter(1))
    assert part.interrupted and part.spp == 0 and part.slices_in_round == 1 and part.spp_text() == "0.00391"
    assert np.isfinite(part.image).all() and (part.image > 0).all()
    reached = part.film.sample_counts() > 0
    assert 0 < reached.mean() < 0.02 and np.isfinite(part.variance[~reached]).sum() == 0


def test_restore_refuses_a_state_of_other_types(scene_path):
    from renderer.film.accumulation import Film

    film = Film(8, 4)
    good = film_state(8, 4, 2.0)
    film.restore(good)
    assert (film.sample_counts() == 2).all() and (film.mean_image() == 2.0).all()
    bad = FilmState(good.mean.astype(np.float64), good.m2, good.count, good.rejected)
    with pytest.raises(ValueError, match="'mean' is float64"):
        film.restore(bad)
    with pytest.raises(ValueError, match="active size"):
        film.restore(film_state(9, 4, 1.0))


@pytest.mark.parametrize("damage, expected", [
    (lambda p: p.write_bytes(b"not a zip at all"), "not a Lantern checkpoint"),
    (lambda p: p.write_bytes(p.read_bytes()[: len(p.read_bytes()) // 2]), "checkpoint"),
    (lambda p: p.unlink(), "checkpoint not found"),
])
def test_damaged_checkpoints_are_one_line_errors(tmp_path, scene_path, damage, expected):
    path = tmp_path / "a.ckpt"
    save_checkpoint(path, header_for(scene_path), film_state(24, 16, 1.0))
    damage(path)
    with pytest.raises(SceneError) as error:
        load_checkpoint(path)
    message = str(error.value)
    assert message.startswith(f"{path}: ") and expected in message and "\n" not in message


def test_a_header_of_another_format_or_size_is_refused(tmp_path, scene_path):
    path = tmp_path / "a.ckpt"
    save_checkpoint(path, header_for(scene_path, format=7), film_state(24, 16, 1.0))
    with pytest.raises(SceneError, match="format 7"):
        read_header(path)
    save_checkpoint(path, header_for(scene_path, width=30), film_state(24, 16, 1.0))
    with pytest.raises(SceneError, match="film 24x16, header 30x16"):
        load_checkpoint(path)


def test_mismatches_name_what_differs(tmp_path, scene_path):
    mine = header_for(scene_path)
    assert mine.mismatches(header_for(scene_path, out="elsewhere.png", exposure=2.0, spp_target=99)) == []
    other_scene = tmp_path / "t.toml"
    other_scene.write_text(furnace_toml(env=0.7, albedo=0.6, max_depth=3))
    problems = mine.mismatches(header_for(other_scene, width=32, integrator="nee", seed=4, lantern_version="9.9"))
    text = "; ".join(problems)
    assert len(problems) == 5, text
    for part in ("Lantern 0.", "is not the checkpoint's", "size 32x16 differs", "integrator nee differs",
                 "seed 4 differs"):
        assert part in text


def test_scene_fingerprint_follows_every_file_the_scene_reads(tmp_path):
    import shutil

    from renderer.scene.catalog import resolve_scene

    folder = tmp_path / "copy"
    shutil.copytree(resolve_scene("bunnies").parent.parent, folder)  # the shipped assets (2 MB)
    scene = load_scene(folder / "scenes" / "bunnies.toml")
    files = scene_files(scene)
    assert files == [(folder / name).resolve() for name in ("scenes/bunnies.toml", "envmaps/sky.exr",
                                                             "models/bunny.glb")]
    before = scene_fingerprint(scene)
    assert scene_fingerprint(load_scene(folder / "scenes" / "bunnies.toml")) == before
    with open(files[-1], "ab") as f:  # a model file changes, the scene file does not
        f.write(b"\n")
    assert scene_fingerprint(scene) != before


def test_pass_size_follows_time_not_only_samples():
    round_ = ROUND_SLICES
    assert pass_slices(None, 64, 1000, None) == 1  # the compiling pass: one slice
    assert pass_slices(0.001 / round_, 1, 10_000 * round_, None) == 4  # grows at most 4x
    assert pass_slices(0.001 / round_, 1000 * round_, 10_000 * round_, None) == 500 * round_  # about half a second
    assert pass_slices(0.001 / round_, 1000 * round_, 30 * round_, None) == 30 * round_  # not past the target
    assert pass_slices(0.001 / round_, 1000 * round_, 10_000 * round_, 0.05) == 50 * round_  # nor the time budget
    # A sample per pixel of 2 s: a pass is the share of it that fits half a second, 64 of 256 slices.
    assert pass_slices(2.0 / round_, 1000, 10_000, None) == int(0.5 / (2.0 / round_)) == 64
    assert pass_slices(1e3, 1000, 10_000, None) == 1  # never less than one slice


class FakeFilm:
    """What CheckpointPolicy reads of a film."""

    def state(self) -> FilmState:
        return film_state(24, 16, 3.0)


def test_automatic_checkpoint_starts_with_a_long_render_and_goes_when_it_completes(tmp_path, scene_path,
                                                                                     monkeypatch):
    import io

    import renderer.commands.render as command
    from renderer.commands.headless import RenderResult

    clock = [1000.0]
    monkeypatch.setattr(command.time, "monotonic", lambda: clock[0])
    path = tmp_path / "out.png.ckpt"
    said = io.StringIO()
    policy = command.CheckpointPolicy(path, 30.0, header_for(scene_path, automatic=True), active=False, stream=said)
    policy.after_pass(FakeFilm(), 10, 5.0, expected_seconds=command.LONG_RENDER_SECONDS)  # not long: nothing
    assert not policy.active and not path.exists() and said.getvalue() == ""
    policy.after_pass(FakeFilm(), 20, 6.0, expected_seconds=300.0)
    assert policy.active and f"checkpointing to {path} every 30 s" in said.getvalue() and not path.exists()
    clock[0] += 29.0
    policy.after_pass(FakeFilm(), 30, 35.0, expected_seconds=300.0)
    assert not path.exists()
    clock[0] += 1.0
    policy.after_pass(FakeFilm(), 40, 36.0, expected_seconds=300.0)
    assert read_header(path).spp_done == 40 and read_header(path).seconds_rendered == 36.0

    result = RenderResult(np.zeros((16, 24, 3), np.float32), 50, 40.0, 0, "path", renderer=FakeFilm(),
                          seconds_rendered=40.0, interrupted=True)
    assert "checkpoint at 50 spp" in policy.finish(result)
    assert read_header(path).spp_done == 50  # kept, to be continued
    result.interrupted = False
    assert policy.finish(result) is None and not path.exists()  # complete: an automatic one goes

    explicit = command.CheckpointPolicy(path, 30.0, header_for(scene_path), active=True, stream=said)
    assert "checkpoint at 50 spp" in explicit.finish(result) and read_header(path).spp_done == 50  # kept


def test_continuing_a_stopped_render_keeps_its_aovs_bit_identical(scene_path):
    """A render that keeps the denoising AOVs, stopped within the samples that bring feature samples
    (renderer/film/aovs.py) and continued: the AOVs and their sample counts are those of the render that
    never stopped, so the count saved with them is what the feature samples' numbers go on from."""
    from pathlib import Path

    from tests.render.test_aovs import PANE_SCENE
    from tests.scene_builder import scene_from_toml

    quad = Path(__file__).resolve().parents[1] / "data" / "textured_quad.glb"  # textured: feature samples
    scene = scene_from_toml(scene_path.parent, PANE_SCENE.format(quad=quad.as_posix(), pane=""), "wall")
    job = RenderJob(spp=12, size=(24, 16), integrator="path", seed=11, aovs=True)
    whole = render(scene, job)
    part = render(scene, job, stop=StopAfter(6))
    assert part.interrupted and 0 < part.mean_spp < 8
    state = part.state
    assert state.aov_count is not None and state.aov_count.max() > state.count.max()
    continued = render(scene, job, resume=Resume(state, part.spp, part.seconds_rendered, part.slices_in_round))
    end, expected = continued.state, whole.state
    assert_same_state(end, expected)
    for name in ("albedo", "normal", "aov_count"):
        np.testing.assert_array_equal(getattr(end, name), getattr(expected, name), err_msg=name)
    assert (expected.aov_count == 12 + 4 * 8).all()
