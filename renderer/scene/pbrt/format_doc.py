"""The "pbrt-v4 scenes" section of docs/scene-format.md: what the reader maps onto what, and what it
leaves out. Kept beside the reader so that a change to the mapping changes its documentation in the
same place; renderer/scene/schema_docs.py appends it to the generated page."""

PBRT_SECTION = """\
## pbrt-v4 scenes

A pbrt-v4 scene file (`.pbrt`, or gzip-compressed `.pbrt.gz`) opens wherever a scene is taken:
`python app.py view scene.pbrt`, `render scene.pbrt`, `info scene.pbrt`. It is read into the same
description a TOML scene becomes (renderer/scene/pbrt/).

The file layer: pbrt-v4's tokens (quoted strings, numbers, `[ ]` lists, `#` comments), `Include`
and `Import` (both spliced in where they stand; a loop is an error naming the chain), relative
file names (includes, meshes, images, spectrum files) looked up as pbrt-v4 looks them up, in the
folder of the scene file given, then in the folder of the file that names them, typed parameters (`integer`, `float`, `point2`, `vector2`, `point3`,
`vector3`, `normal`, `rgb`, `spectrum`, `blackbody`, `bool`, `string`, `texture`), the graphics
state (`AttributeBegin` / `End`, `TransformBegin` / `End`, `ReverseOrientation`, `Material`,
`MakeNamedMaterial` / `NamedMaterial`, `Texture`, `MakeNamedMedium` / `MediumInterface`,
`AreaLightSource`), transforms composed as pbrt composes them (`Identity`, `Translate`, `Scale`,
`Rotate`, `LookAt`, `Transform` and `ConcatTransform` column by column, `CoordinateSystem`,
`CoordSysTransform`, the `camera` and `world` systems), and `ObjectBegin` / `End` with
`ObjectInstance`. `rgb` values are used as written; a `spectrum` (wavelength-value pairs or a
file of them) becomes RGB as a Mitsuba scene's does (renderer/spectral/mitsuba_rgb.py); light
spectra and `blackbody` are normalised to luminance 1 first, as pbrt-v4 normalises them.

| pbrt-v4 | Lantern |
|---|---|
| `Camera "perspective"` (`fov`, for the image's shorter side; `lensradius`, `focaldistance`) | the camera (vertical field of view; a thin lens) |
| `Camera "orthographic"` | an orthographic camera 2 units across the shorter side |
| pbrt's left-handed camera space (image right = camera +x; a bare `LookAt` shows the world mirrored against a right-handed camera, which is why exported scenes begin with `Scale -1 1 1`) | the image pbrt renders: where it is mirrored against Lantern's right-handed camera the scene (shapes and lights) is reflected through the plane of the camera's forward and up directions |
| `Film "rgb"` (`xresolution`, `yresolution`, by default 1280 x 720; `cropwindow`) | the image size; `render.crop` with pbrt's pixel bounds (ceil of each fraction times the size) |
| `Film` `iso` (100) with the `Camera`'s `shutteropen` and `shutterclose` (0, 1) | `render.exposure` = log2(shutter time x iso / 100), pbrt-v4's imaging ratio as a display exposure: PNG output and the viewer show what pbrt's image shows, Lantern's EXR keeps radiance (pbrt's is radiance times the ratio); `whitebalance` and a `sensor` other than `cie1931`: a warning, no white balance |
| `Sampler` (`pixelsamples`, by default 16; `stratified`: `xsamples` x `ysamples`; `seed`) | `spp` and the seed; `independent` is Lantern's `independent`, the others its `sobol` |
| `Integrator` `volpath` (the default), `path`, `bdpt`, `mlt`, `lightpath`, `simplepath`, `simplevolpath`, `randomwalk` (`maxdepth`, by default 5) | `mis` with max_depth = maxdepth + 1 (pbrt counts bounces, 1 being direct light; Lantern counts as Mitsuba, 2 being direct light); energy compensation off, as pbrt's rough BSDFs scatter once; the integrators other than `volpath` and `path` with one line saying so |
| `Integrator` `sppm` (`maxdepth`; `radius` warned) | Lantern's `sppm` (photon mapping finds the caustics of small lights behind glass), its search radius starting at two pixel footprints; `mis` with a warning in scenes with media or point, spot and distant lights, which Lantern's photons do not serve |
| `PixelFilter` `gaussian` (the default; `sigma`), `triangle` (`xradius`), `box` (radius 0.5) | the `gaussian` (cut at four deviations where pbrt cuts at its radius), `tent` and `box` filters; `mitchell`, `sinc`: the box filter, with a warning |
| `diffuse` (`reflectance` a colour or texture) | `diffuse` |
| `conductor` (`eta` and `k` as `metal-X-eta` / `metal-X-k` named spectra, Lantern's measured metal X, by default copper; as `rgb` or sampled spectra; or `reflectance`) | `conductor` with `metal`, `eta` and `k`; a `reflectance` r as pbrt makes it an index, eta 1 and k = 2 sqrt(r / (1 - r)) (a textured one: Schlick's Fresnel from it, a warning) |
| `roughness`, `uroughness`, `vroughness`, `remaproughness` (by default true) | alpha = sqrt(r) when remapped, else r; Lantern's `roughness` = sqrt(alpha) (`roughness_v` where v differs), GGX with height-correlated masking (`microfacet` `ggx`) as pbrt's; alpha below 0.001 is smooth; a texture of roughness is a textured width (a checkerboard's two widths remapped as pbrt remaps; an image only with `remaproughness false`); under a coat, a warning and a checkerboard's mean width |
| `dielectric`, `thindielectric` (`eta` a number, a sampled spectrum read at 550 nm, or `glass-BK7`, `-BAF10`, `-FK51A`, `-LASF9`, `-F5`, `-F10`, `-F11` at 550 nm) | `dielectric` (`thin` for `thindielectric`), without dispersion |
| `interface` (and no material, `""` or `none`) | `null` |
| `mix` (`materials`, two named materials; `amount` a number or a texture) | a mix (`MaterialSpec.mix`): the second with probability `amount` (a texture's first channel), as pbrt chooses per point |
| `coateddiffuse` (`reflectance`, `roughness` / `uroughness` / `vroughness`, `eta`, `thickness`, `albedo`, `g`, `maxdepth`, `nsamples`) | `coated` with `coat_base = "diffuse"`: pbrt-v4's stochastic layered BSDF itself, its random walk between the interface and the base (renderer/materials/coated.py) |
| `coatedconductor` (`interface.*` roughness and `eta`, `conductor.eta` / `conductor.k` or `reflectance`, `conductor.roughness`, the slab's parameters) | `coated` with `coat_base = "conductor"` (an anisotropic conductor under the coat: its u roughness, a warning) |
| `diffusetransmission` (`reflectance`, `transmittance`, each a colour or texture, `scale`) | `diffuse_transmission`: Lambert reflection and transmission, chosen in proportion to their largest channels as pbrt does |
| `Texture` `imagemap` (`filename`, `filter` `point` nearest else bilinear, `encoding` `sRGB` or `linear` (by default linear for .exr, .hdr, .pfm), `scale`, `wrap` `repeat` or `clamp`, `uscale`, `vscale`, `udelta`, `vdelta`) | a bitmap texture on a colour, times `scale`; pbrt's v (up the image) turned into Lantern's (down it) |
| `Texture` `checkerboard` (2D, constant `tex1`, `tex2`, `uscale`, `vscale`), `constant` | a checkerboard texture, a colour |
| `Texture` `scale` (`tex` times `scale`) and `mix` (`(1 - amount) tex1 + amount tex2`; `amount` a float texture's first channel), each operand a colour, a number or a texture | a colour where no operand is a texture; a texture times colours where one is; else one image baked texel by texel when the scene is assembled (kind `mix` or `product`, renderer/scene/texture_mixing.py), exact where the textures share a size and a uv mapping (different mappings: a warning, the first's used for all; other sizes resampled to the largest) |
| `Shape` `trianglemesh` (`P`, `indices`, `N`, `uv`), `bilinearmesh` (two triangles per patch), `loopsubdiv` (its control mesh, a warning) | meshes kept inside the scene's own model asset (named parts of the scene file) |
| `Shape` `plymesh` (`.ply`, or `.ply.gz` decompressed) | the PLY mesh; a missing file: one warning, the shape left out |
| `Shape` `sphere` (`radius`) | an analytic sphere (an icosphere under a non-uniform scale); `zmin`, `zmax`, `phimax` cutting it: a warning, the whole sphere |
| `Shape` `disk` (`radius`, `height`), `cylinder` (`radius`, `zmin`, `zmax`) | the `disc_fan` and `cylinder` meshes (`innerradius`, `phimax`: a warning) |
| texture coordinates | a mesh's own (`uv`, the PLY file's); spheres, disks and cylinders carry Lantern's analytic shapes' and generators' coordinates, not pbrt's (u along phi, v along theta or the radius) |
| `ReverseOrientation` and mirroring transforms | the shape's front side turned over as in pbrt (which side emits, which side bounds a medium) |
| `AreaLightSource "diffuse"` (`L`, `scale`, `power`, `twosided`) | the emission of the shapes that follow, one-sided as pbrt's default, from both faces where `twosided` (`two_sided_emission`); with `power`, times power / (pi area) as pbrt-v4 has it, the area being that of each light pbrt makes of the shape (a sphere, disk or cylinder whole, each triangle of a mesh, each bilinear patch; parts of unequal area: their mean, with a warning), twice it where `twosided` (an image `filename`: a warning) |
| `LightSource` `point` (`from`, `I`, `scale`, `power`), `spot` (`from`, `to`, `coneangle`, `conedeltaangle`, `power`), `distant` (`from`, `to`, `L`, `scale`, `illuminance`) | `[[lights]]` point, spot (cutoff = coneangle, beam = coneangle - conedeltaangle; Lantern's falloff is linear in angle between them where pbrt's is smooth in the cosine) and directional |
| `LightSource "infinite"` with `L` (or nothing: white) | a constant environment |
| `LightSource "infinite"` with `filename` (an `.exr` or `.hdr` equal-area square map; `scale`) | an environment map: the square resampled once into a latitude-longitude map (bilinearly, as pbrt looks it up) with the light's rotation and the scene's mirror baked in, cached as an EXR under `$XDG_CACHE_HOME/lantern/pbrt-environments` (by default `~/.cache`); `.pfm` maps too; a missing map: a uniform white environment times `scale`, with a warning |
| a shape's `alpha` (a number or a float texture) | the opacity of its material (a copy for the shape): the coverage, a texture's first channel; Lantern's opacity is stochastic, as pbrt's alpha test |
| `MakeNamedMedium` `homogeneous` (`sigma_a`, `sigma_s`, `scale`, `g`) with `MediumInterface` | the inside medium is the shapes' material's `medium`, the outside one its `outside_medium` unless it is the camera's; the camera's medium (the outside one current at `Camera`) fills the scene as `fog.model = "medium"`; a shape without a transition (inside = outside) keeps the medium a ray is in |
| `MakeNamedMedium` `uniformgrid` (`density` with `nx`, `ny`, `nz`; `p0`, `p1`; `sigma_a`, `sigma_s`, `scale`, `g`) | a grid medium: extinction (sigma_a + sigma_s) scale density over [p0, p1] in the medium's space, the density at cell centres read trilinearly as pbrt's, albedo sigma_s / (sigma_a + sigma_s); emission (`Le`, `temperature`) a warning |

Left out with one warning each, naming file, line and directive, while the rest renders: maps in
formats other than EXR and Radiance HDR, `illuminance`, goniometric and projection lights, other
shapes (curves, cones, paraboloids, hyperboloids), other materials (rendered diffuse 0.5),
other textures (`directionmix`, `bilerp`, `dots`, `fbm`, `wrinkled`, `windy`, `marble`, `ptex`: the parameter's default), media other than `homogeneous` and `uniformgrid` (`rgbgrid`, `cloud`, `nanovdb`) and named scattering
presets, empty space outside a shape while the camera is in a medium, float textures on indices, images of roughness where pbrt remaps them, textures inside a checkerboard,
area lights on object instances, motion blur (`ActiveTransform`,
`TransformTimes`), `Attribute`, `Option`, colour spaces other than sRGB, and any parameter no
mapping reads. A missing image or PLY file is one warning naming it and what stands in. A scene
with nothing left to render, an unterminated string, an unknown directive, a malformed
parameter, an include loop and a missing include are one-line errors naming file and line.
"""
