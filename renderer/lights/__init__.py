"""Lights: every emitter of a scene, for direct lighting and for photon emission.

lights.py             `Lights`: a light sample at a point and its densities (environment, an
                      emissive primitive or a delta light), and the emitter table (power per
                      emissive primitive)
delta_lights.py       point, spot, directional and projector lights: no surface, found by light samples
                      alone, chosen by their contribution at the shading point
light_projection.py   what spots' textures and projectors' images mean: frames, uv, fields of view (numpy)
environment.py        the environment's radiance (map, sky or constant colour)
env_sampling.py       importance sampling of an environment map
light_select.py       choosing one emissive primitive: uniform, by power (alias table) or the tree
light_tree_build.py   the light tree's build (numpy); light_tree.py its device traversal
photon_emission.py    where photons start (SPPM's light paths)
"""
