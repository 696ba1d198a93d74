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
| `orthographic` sensor (the view spans 2 of `to_world`'s x-scales across the image and 2 y-scales / aspect up it) | an orthographic camera, `ortho_height` = 2 y-scale / aspect (x and y scaled unequally: a warning, the height is kept) |
| `hdrfilm` `width`, `height`; `rfilter` `box`, `tent` (`radius`), `gaussian` (`stddev`; the default) | the image size and the pixel filter (other filters: the box, with a warning) |
| `hdrfilm` `crop_offset_x`, `crop_offset_y`, `crop_width`, `crop_height` (offsets 0 and the image's size by default) | `render.crop`: only the window is rendered and written, with the whole image's projection; each pixel equals the whole render's (its filter cut at the image's edges, where Mitsuba's crop leaves out the filter's reach beyond the window: pixels along the window's inner edges differ slightly with a tent or Gaussian filter); a window outside the image or without pixels is an error naming file and line |
| `independent` sampler (`stratified`, `multijitter`, `orthogonal`, `ldsampler`: Lantern's `sobol`) | the sampler and `spp` |
| `path`, `volpath`, `volpathmis`, `ptracer`, `direct` (inside `moment` too) | `mis`, with Mitsuba's `max_depth` (-1 unlimited; `direct` is 2) |
| `depth`, `aov` | the `depth` view |
| `diffuse` | `diffuse` |
| `conductor`, `roughconductor` (`material` by name, `eta` and `k`, none = a mirror; `specular_reflectance` a colour or texture; `alpha` or `alpha_u` and `alpha_v`, numbers or textures; `distribution` `beckmann` (the default) or `ggx`) | `conductor`, one-sided (roughness = sqrt(alpha), `roughness_v` = sqrt(alpha_v); `microfacet` `beckmann` or `ggx_separable`: Mitsuba's distributions with Smith's separable masking; the Fresnel times `specular_color`; `eta` and `k` textured too, their values the index itself; with energy compensation a textured index keeps its untextured mean Fresnel) |
| `dielectric`, `roughdielectric`, `thindielectric` (`int_ior` / `ext_ior` as numbers or names, `specular_transmittance` and `specular_reflectance` colours or textures: the transmission's and the reflection's tints) | `dielectric` (relative index), `thin` for `thindielectric` (as in Mitsuba, passing straight through it is no bounce, shadow rays pass it with its transmittance, and with an `interior` it bounds that medium) |
| `principled`, `principledthin` (every parameter: `base_color`, `roughness`, `anisotropic`, `metallic`, `spec_trans`, `specular` or `eta`, `spec_tint`, `sheen`, `sheen_tint`, `clearcoat`, `clearcoat_gloss`, `flatness`, `diff_trans`; each scalar a number, `bitmap` or `checkerboard`) | `disney` (`thin` for `principledthin`): Mitsuba's model itself, its values and densities equal to Mitsuba's at any pair of directions (tests/materials/test_disney.py); `specular` becomes Mitsuba's index 2 / (1 - sqrt(0.08 specular)) - 1; the back side is the model's inside (dark unless it transmits); sampling rates other than 1: a warning (they change only the noise) |
| `plastic`, `roughplastic` (`diffuse_reflectance` and `specular_reflectance` colours or textures, `int_ior` / `ext_ior`, `nonlinear`, `alpha`, `distribution`) | `plastic`, one-sided: Mitsuba's model, a diffuse base under a smooth or rough dielectric coating with its internal reflections (renderer/materials/plastic_tables.py computes Mitsuba's tables; they agree with Mitsuba's to 0.1%) |
| `twosided` | its BSDF with `sidedness = "two_sided"` (a Mitsuba BSDF is one-sided: `back_black`; dielectrics, thin dielectrics, `principledthin` and `null` shade both sides; around a `principled`, `front_both_sides`: its back shades as its front; a second BSDF for the back face: a warning) |
| `null` | `null` (crossing it is no bounce) |
| `mask` (`opacity` a number, `bitmap` or `checkerboard`) | the BSDF inside with stochastic coverage: a ray meets the surface with probability `opacity` (the texture's first channel) |
| `normalmap` (`normalmap` a `bitmap`, read raw where `raw` is set, a `checkerboard` or a `rawconstant`) | the BSDF inside with its shading normal 2 rgb - 1 in Mitsuba's shading frame (tangent along dp/du, per triangle as Mitsuba 3.9 has it), mirrored where the viewer is behind it, and Mitsuba's shadow-terminator term (Estevez et al. 2019); `flip_invalid_normals` and `use_shadowing_function` false: warnings, drawn as true |
| `bumpmap` (one height texture as for `normalmap`, `scale`) | the BSDF inside with its normal from dp/du and dp/dv lifted by `scale` times the height's gradient (the derivative of the bilinear lookup; luminance of a colour image), as `normalmap` otherwise; a map inside another map: a warning, the outer one is used |
| `blendbsdf` (`weight` a number, `bitmap` or `checkerboard`; nested up to 4 deep) | a mix (`MaterialSpec.mix`): at each shading point the second BSDF with probability `weight`, else the first, as pbrt-v4's mix material chooses, so the image is Mitsuba's weighted sum in expectation; the mix keeps its emitter, medium, mask and normal or bump map; a `mask` inside it: a warning |
| `blendbsdf` of two `diffuse` BSDFs with plain colours, `weight` a number or a `mesh_attribute` | one `diffuse` BSDF coloured (1 - w) r0 + w r1, per vertex or face for an attribute |
| `mesh_attribute` texture (`name` vertex_... or face_..., `scale`) on a diffuse reflectance, principled base colour or plastic's diffuse (inside `twosided`, `mask`, `bumpmap`, `normalmap` too) | per-corner colours read from the PLY mesh's attribute (properties `<prefix>_0`, `_1`, `_2` or one, as Mitsuba groups them; `red`, `green`, `blue` as fractions of 255: Mitsuba reads them raw), per face by giving each triangle its own vertices; a missing attribute is an error naming the file |
| `bitmap` (`filter_type`, `wrap_mode`, `raw`, `to_uv`) and `checkerboard` textures on a diffuse reflectance, principled base colour or plastic's diffuse; on a rough BSDF's `alpha` / `alpha_u` / `alpha_v`, a `mask`'s `opacity`, and every scalar of `principled` and `principledthin` | a base colour texture (nearest or bilinear); on a scalar, its first channel (a checkerboard read as a number takes the other parity, as Mitsuba's does) |
| `obj`, `ply`, `serialized` (`shape_index`; versions 3 and 4), with `face_normals`, `flip_normals`, `flip_tex_coords` (OBJ on, PLY off by default) | meshes placed by `to_world`; a file without normals gets angle-weighted vertex normals, as in Mitsuba |
| `sphere` (`center`, `radius`), `rectangle`, with `flip_normals` | analytic spheres (texture coordinates in `to_world`'s frame) and quads; `flip_normals` turns the normal over and keeps the texture coordinates, as Mitsuba's: the front (emitting side of an area emitter, lit side of a one-sided BSDF) and the inside of media swap, a flipped sphere emits inwards; a mirroring `to_world` turns a sphere inwards and keeps a rectangle's transformed normal, as in Mitsuba |
| `disk`, `cube`, `cylinder` (`p0`, `p1`, `radius`; open, no caps) with `flip_normals` | the `disc_fan`, `cube` and `cylinder` generators' meshes with Mitsuba's texture coordinates (the disk and the tube finely tessellated with exact normals: within 5e-6 of the radius; any `to_world`, so an elliptical disk) |
| `shapegroup`, `instance` | each instance draws its group's shapes placed by its `to_world` (stored once per instance) |
| `area` emitter on a shape (`radiance` a colour, or a `bitmap` or `checkerboard` texture) | the shape's material with that emission (one-sided), textured over the shape's texture coordinates |
| `constant`, `envmap` (`scale`, `to_world` any rotation, a mirror included) | the environment; a rotation about +y is its `rotation`, any other its full 3x3 rotation, looked up at to_world^-1 d as in Mitsuba (a to_world that scales or shears: a warning, its rotation part is kept; translation is ignored, as in Mitsuba) |
| `point` (`position` or `to_world`, `intensity`), `spot` (`to_world`, `intensity`, `cutoff_angle`, `beam_width`, a projected `bitmap` or `checkerboard` `texture`), `directional` (`direction` or `to_world`, `irradiance`) | `[[lights]]` of those types, with `up` the to_world's +y (a texture on a spot with a cutoff of 90 degrees or more maps nowhere: a warning, the spot is untextured) |
| `projector` (`irradiance` a texture or a colour, `scale`, `fov` with `fov_axis` or `focal_length`, `to_world`) | a `projector` light: irradiance = colour (or white under the image) times `scale`, times the to_world's uniform scale as in Mitsuba (uneven scale or shear: a warning) |
| `homogeneous` medium as a shape's `interior` (`sigma_t`, `albedo`, `scale`, `isotropic` or `hg` phase) | a medium inside the shape's material |
| `heterogeneous` medium (`sigma_t` and `albedo` as `gridvolume` from a `.vol` file with `to_world`, `use_grid_bbox`, `filter_type` trilinear or nearest; as `constvolume` or a value; `scale`) | a `grid` medium inside the shape's material, only within the `sigma_t` volume's box as in Mitsuba (delta tracking, ratio tracking for shadow rays; `wrap_mode` other than clamp: a warning) |

Left out with one warning each, naming file, line and plugin, while the rest renders: other
emitters, other shapes (curves, hair, `sdfgrid`), media other than these two and volumes other than grids and constants, textures on other parameters, exterior media, and
any parameter no mapping reads. A scene with nothing left to render, malformed XML
(line and column), a `$name` with no value, an include loop and a missing file are one-line errors.

`python app.py bench mitsuba-tests --data DIR` renders Mitsuba's own render tests (the
mitsuba-data repository's tests/scenes) and judges each by Mitsuba's z-test; its table is on the
benchmark page.
"""
