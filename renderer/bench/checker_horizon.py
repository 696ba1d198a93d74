"""The texture-filtering test scene: a fine checkerboard on a white diffuse plane to the horizon
under a white sky. With max_depth 2 and the `path` integrator a sample of the plane is its albedo
exactly (a cosine-sampled bounce always reaches the sky, of radiance 1), so all the noise of a
render is the texture's aliasing, which filtering is there to remove."""
from dataclasses import replace

from renderer.scene.description import Scene, TextureSpec
from renderer.scene.load_options import LoadOptions
from renderer.scene.toml_loader import scene_from_toml

CHECKS_PER_SIDE = 400  # the plane is 400 m wide: a check is half a metre, a texel of the 2x2 image

_SCENE = {
    "scene": {"name": "checker_horizon", "geometry": "mesh"},
    "camera": {"position": [0, 1, 0], "look_at": [0, 0.8, -10], "up": [0, 1, 0], "fov": 50},
    "render": {"width": 64, "height": 32, "spp": 1, "max_depth": 2, "integrator": "path"},
    "environment": {"type": "constant", "color": [1, 1, 1]},
    "materials": {"floor": {"type": "diffuse", "base_color": [1, 1, 1]}},
    "objects": [{"type": "quad", "material": "floor", "size": [400, 400]}],
}


def checker_horizon(texture_filter: str = "anisotropic") -> Scene:
    """The scene with its render settings' `texture_filter`."""
    scene = scene_from_toml(_SCENE, "checker_horizon.toml", LoadOptions())
    scale = CHECKS_PER_SIDE / 2.0  # the 2x2 checkerboard image repeated
    checker = TextureSpec("checkerboard", nearest=True, color0=(0.9,) * 3, color1=(0.1,) * 3,
                          transform=((scale, 0.0, 0.0), (0.0, scale, 0.0), (0.0, 0.0, 1.0)))
    floor = replace(scene.materials[0], base_color_texture=checker)
    return replace(scene, materials=(floor,), render=replace(scene.render, texture_filter=texture_filter))
