"""Textures made of two (pbrt's mix and scale), baked into one image: the formula per texel,
operands of other sizes resampled at texel centres, and the bytes charged to the budget."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from renderer.scene.description import TextureSpec
from renderer.scene.errors import SceneError
from renderer.scene.limits import MemoryBudget, MemoryLedger
from renderer.scene.texture_images import texture_image


def ledger(limit=1 << 30):
    return MemoryLedger(MemoryBudget(limit, "the test's limit"))


def png(tmp_path, name, pixels):
    Image.fromarray(np.asarray(pixels, np.uint8)).save(tmp_path / name)
    return TextureSpec("bitmap", file=tmp_path / name)


def linear(spec):
    return texture_image(spec, ledger()).linear()[..., :3]


def test_a_mix_is_the_formula_at_every_texel(tmp_path):
    rng = np.random.default_rng(3)
    first = png(tmp_path, "a.png", rng.integers(0, 256, (3, 5, 3)))  # sRGB: decoded before mixing
    amount = png(tmp_path, "m.png", rng.integers(0, 256, (3, 5, 3)))
    spec = TextureSpec("mix", operands=(((0.5, 1.0, 2.0), first), ((0.1, 0.2, 0.3), None)), amount=(0.8, amount))
    image = texture_image(spec, ledger())
    a = 0.8 * linear(amount)[..., :1]
    expected = (1 - a) * linear(first) * (0.5, 1.0, 2.0) + a * np.array([0.1, 0.2, 0.3])
    assert not image.srgb and image.shape == (3, 5)
    np.testing.assert_allclose(image.pixels[..., :3], expected, rtol=1e-6, atol=1e-7)
    assert (image.pixels[..., 3] == 1).all()


def test_a_product_resamples_the_smaller_operand_at_texel_centres(tmp_path):
    checks = TextureSpec("checkerboard", color0=(1.0, 1.0, 1.0), color1=(0.0, 0.0, 0.0), nearest=True)
    ramp = png(tmp_path, "r.png", np.full((4, 4, 3), 255))
    nearest = TextureSpec("product", operands=(((2.0,) * 3, ramp), ((1.0,) * 3, checks)), nearest=True)
    got = texture_image(nearest, ledger()).pixels[..., 0]
    np.testing.assert_array_equal(got, 2.0 * np.kron([[1, 0], [0, 1]], np.ones((2, 2))))  # 2x2 blocks
    bilinear = TextureSpec("product", operands=(((1.0,) * 3, ramp), ((1.0,) * 3, checks)), wrap="clamp")
    got = texture_image(bilinear, ledger()).pixels[..., 0]
    # target texel centres 1/8, 3/8, ... fall at source x = -1/4, 1/4, 3/4, 5/4 (clamped at the edge)
    column = np.array([1.0, 0.75, 0.25, 0.0])
    np.testing.assert_allclose(got[0], column, atol=1e-6)
    np.testing.assert_allclose(got[:, 0], column, atol=1e-6)


def test_a_mix_beyond_the_budget_is_refused(tmp_path):
    big = png(tmp_path, "b.png", np.zeros((64, 64, 3)))
    spec = TextureSpec("mix", operands=(((1.0,) * 3, big), ((1.0,) * 3, None)))
    alone = ledger()
    texture_image(big, alone)  # the operand fits; its mix does not
    with pytest.raises(SceneError, match="mix texture"):
        texture_image(spec, ledger(alone.high_water + 1024))


def test_colours_alone_are_not_an_image():
    with pytest.raises(ValueError, match="a colour"):
        texture_image(TextureSpec("mix", operands=(((1.0,) * 3, None), ((0.0,) * 3, None))), ledger())
