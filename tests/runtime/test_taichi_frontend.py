"""The cheaper Taichi front end (renderer/runtime/taichi_frontend.py): installed, same kernels, errors
still say where."""
import pytest
import taichi as ti

from renderer.runtime import taichi_frontend


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


def test_source_lines_are_wrapped_as_textwrap_does_and_remembered():
    import textwrap

    from taichi.lang import kernel_impl

    assert taichi_frontend.install() is True
    lines = ["\tx = 1", "    y = [a,\tb]  # a comment", "", "z" * 20000]
    for line in lines + lines:  # the second round comes from the cache
        assert kernel_impl.textwrap.fill(line, tabsize=4, width=9999) == textwrap.fill(line, tabsize=4, width=9999)
    assert kernel_impl.textwrap.dedent("  a\n  b") == "a\nb"  # everything else is the module's own
