"""The cheaper Taichi front end (renderer/taichi_frontend.py): installed, same kernels, errors
still say where."""
import pytest
import taichi as ti

from renderer import taichi_frontend


def test_installs_once_on_this_taichi():
    assert taichi_frontend.install() is True
    assert taichi_frontend.install() is True  # idempotent: the second call patches nothing again


def make_scaler(factor):
    @ti.func
    def scaled(x):
        return x * factor

    return scaled


def test_closures_of_one_function_compile_with_their_own_values():
    """The source cache is per code object; each closure still captures its own constant."""
    taichi_frontend.install()
    double, triple = make_scaler(2.0), make_scaler(3.0)
    out = ti.field(ti.f32, shape=2)

    @ti.kernel
    def fill():
        out[0] = double(1.5)
        out[1] = triple(1.5)

    fill()
    assert out.to_numpy().tolist() == [3.0, 4.5]


def test_a_compile_error_still_names_the_file_line_and_source():
    taichi_frontend.install()

    @ti.kernel
    def broken() -> ti.f32:
        return undefined_name_here + 1.0  # noqa: F821

    with pytest.raises(Exception) as raised:
        broken()
    text = str(raised.value)
    assert __file__ in text and "undefined_name_here + 1.0" in text and "in broken" in text
    assert "^" in text
