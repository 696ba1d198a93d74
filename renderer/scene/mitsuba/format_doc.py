"""The "Mitsuba 3 scenes" section of docs/scene-format.md: what the reader maps onto what, and what it
leaves out. Kept beside the reader so that a change to the mapping changes its documentation in the
same place; renderer/scene/schema_docs.py appends it to the generated page."""

MITSUBA_SECTION = """\
## Mitsuba 3 scenes

A Mitsuba 3 scene file (`.xml`) opens wherever a scene is taken: `python app.py view scene.xml`,
`render scene.xml`, `info scene.xml`, `compare scene.xml`. `-D NAME=VALUE` (repeatable) gives a
`$NAME` parameter, over the file's `<default>`, as Mitsuba's `-D` does. The file is read with the
standard library's expat parser into the same description a TOML scene becomes
(renderer/scene/mitsuba/).

The file layer: `<include>` (a loop is an error naming the chain), `<path>` (searched latest
first, then the including file's folder), `<default>`, `$name`, `id` and `<ref>` (named or not),
nested plugins, transforms composed in the order written (`translate`, `rotate`, `scale`,
`matrix` of 16 or 9 numbers, `lookat`), values `integer`, `float`, `boolean`, `string`, `point`,
`vector`, `rgb`, `spectrum` (one number, `wavelength:value` pairs or a file). A spectrum becomes
RGB as Mitsuba's RGB variants make it: integrated against the CIE 1931 curves (renderer/spectral/
mitsuba_rgb.py), reflectances under D65 and clamped to [0, 1], emission and indices unclamped.

| Mitsuba | Lantern |
|---|---|
| `perspective`, `thinlens` sensor (`fov` with `fov_axis` x, y, diagonal, smaller, larger; `focal_length`, by default 50 mm on 35 mm film) | the camera (vertical field of view; a thin lens with `aperture_radius`, `focus_distance`) |
| `hdrfilm` `width`, `height`; `rfilter` `box`, `tent` (`radius`), `gaussian` (`stddev`; the default) | the image size and the pixel filter (other filters: the box, with a warning) |
| `independent` sampler (`stratified`, `multijitter`, `orthogonal`, `ldsampler`: Lantern's `sobol`) | the sampler and `spp` |
| `path`, `volpath`, `volpathmis`, `ptracer`, `direct` (inside `moment` too) | `mis`, with Mitsuba's `max_depth` (-1 unlimited; `direct` is 2) |
| `depth`, `aov` | the `depth` view |
| `diffuse` | `diffuse` |
| `conductor`, `roughconductor` (`material` by name, `eta` and `k`, none = a mirror; GGX `alpha`) | `conductor` (roughness = sqrt(alpha); Beckmann is rendered as GGX, anisotropic alpha as its mean: warnings) |
| `dielectric`, `roughdielectric`, `thindielectric` (`int_ior` / `ext_ior` as numbers or names) | `dielectric` (relative index), `thin` for `thindielectric` |
| `principled`, `principledthin` | `principled` (base colour, roughness, metallic, `spec_trans`, `eta`; Disney's clearcoat, sheen, anisotropy and specular tint: warnings) |
| `plastic`, `roughplastic` | approximated by `principled` with the diffuse colour, roughness and index (a warning) |
| `twosided` | its BSDF (Lantern's surfaces shade both sides) |
| `null` | `null` (crossing it is no bounce) |
| `bumpmap`, `normalmap`, `mask`, `blendbsdf` | the BSDF inside (a warning) |
| `bitmap` (`filter_type`, `wrap_mode`, `raw`, `to_uv`) and `checkerboard` textures on a diffuse reflectance, principled base colour or plastic's diffuse | a base colour texture (nearest or bilinear) |
| `obj`, `ply`, `sphere` (`center`, `radius`), `rectangle`, `disk`, `cube` | meshes, spheres, quads and discs placed by `to_world` |
| `area` emitter on a shape | the shape's material with that emission (one-sided) |
| `constant`, `envmap` (`scale`, `to_world` rotating about +y) | the environment |
| `point` (`position` or `to_world`, `intensity`), `spot` (`to_world`, `intensity`, `cutoff_angle`, `beam_width`), `directional` (`direction` or `to_world`, `irradiance`) | `[[lights]]` of those types (a spot's projected `texture`: a warning, the spot is untextured) |
| `homogeneous` medium as a shape's `interior` (`sigma_t`, `albedo`, `scale`, `isotropic` or `hg` phase) | a medium inside the shape's material |

Left out with one warning each, naming file, line and plugin, while the rest renders: `projector`
emitters, other shapes (`cylinder`, `serialized`, `shapegroup` and `instance`, curves, hair,
`sdfgrid`), heterogeneous media and grid volumes, textures on other parameters, exterior media, crop
windows, and any parameter no mapping reads. A scene with nothing left to render, malformed XML
(line and column), a `$name` with no value, an include loop and a missing file are one-line errors.

`python app.py bench mitsuba-tests --data DIR` renders Mitsuba's own render tests (the
mitsuba-data repository's tests/scenes) and judges each by Mitsuba's z-test; its table is on the
benchmark page.
"""
