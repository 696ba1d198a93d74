"""Which renders the packet path takes: the CPU, and scenes whose every part has a lane-by-lane
form (renderer/packets/). Anything else renders with the scalar RenderProgram, as before; the
reason is said once per render (`unsupported` gives it)."""
from __future__ import annotations

import taichi as ti

from renderer.materials.kinds import KINDS
from renderer.packets.traversal import PACKET_KINDS

PACKET_INTEGRATORS = ("path", "nee", "mis")
# Lambert's in lane arithmetic; the others through the scalar BSDF lane by lane (renderer/packets/path.py).
# Not the null boundary, whose crossing the scalar tracer counts apart from bounces.
PACKET_MATERIALS = frozenset(kind.name for kind in KINDS) - {"null"}
# Features the scalar BSDF takes care of at the geometry's own surface record: with any of them on,
# every lane is shaded through it (renderer/packets/program.py)
SURFACE_FEATURES = ("has_textures", "has_normal_maps", "has_mapped_frames", "has_bump_maps", "has_anisotropy",
                    "has_mixes", "has_vertex_colors", "has_sidedness")
# Features that must be off, with the words that say so
_EFFECTS = (("has_media", "participating media"), ("analytic_fog", "fog"), ("has_dispersion", "dispersion"),
            ("has_alpha", "alpha coverage"), ("has_instances", "instances"),
            ("has_flipped_normals", "turned-over normals"), ("has_thin", "thin walls"),
            ("depth_of_field", "depth of field"), ("orthographic", "an orthographic camera"),
            ("has_light_textures", "light textures"))
PACKET_WIDTHS = (4, 8, 16)
# From this many primitives on, a packet's bounce and shadow rays go through the scalar traversal
# one lane after another (traversal.trace_lanes); its camera rays stay a packet. Incoherent rays
# spread a packet over many more nodes than any one ray visits (scripts/packet_speed.py's random
# rays, closest + shadow: the 1M-triangle stress scene 2.44 M rays/s in packets of 4 against 5.10
# one at a time; bunnies, studio, many_lights (15-26k primitives) 14.7 / 23.3 / 6.8 against 12.0 /
# 13.7 / 6.4). Whole renders of stress: packets 0.72x the scalar path, with scalar bounces 1.00x.
# Whole `mis` renders in packets of 4 against one ray at a time, packet / scalar bounces
# (docs/findings.md, "Bounce rays one at a time from 32,000 primitives"): Mitsuba's 61,600-triangle
# material-preview mesh 0.78x / 1.00x (textured: 0.78x / 0.92x); many_lights (25.7k) 3.01x /
# 3.03x; bunnies (17.0k) 1.11x / 1.05x; studio (14.8k) 1.02x / 1.06x. The threshold lies between
# the bunnies and the preview mesh (their geometric mean, rounded).
SCALAR_BOUNCE_PRIMITIVES = 32_000


def scalar_bounces(geometry) -> bool:
    """Whether the packet path traces this world's bounce and shadow rays one lane at a time."""
    return int(geometry.primitive_count()) >= SCALAR_BOUNCE_PRIMITIVES


def on_cpu() -> bool:
    return ti.lang.impl.current_cfg().arch in (ti.x64, ti.arm64)


def unsupported(geometry, features, integrator: str, sampler: str, feature_samples: bool,
                textured_emission: bool = False) -> str | None:
    """None where the packet path renders this combination, else why not (a short phrase).
    feature_samples: the AOVs are kept with feature samples (renderer/film/aovs.py).
    textured_emission: a material's emission is textured (the packet path's lights emit their
    material's one colour)."""
    if not on_cpu():
        return "the packet path is for the CPU (GPUs run 32 lanes of their own)"
    if features.geometry != "mesh":
        return "SDF scenes are marched one ray at a time"
    if integrator not in PACKET_INTEGRATORS:
        return f"the {integrator} integrator has no packet form"
    if sampler != "independent":
        return f"the {sampler} sampler has no packet form"
    if feature_samples:
        return "the denoiser's feature samples (textured scenes' AOVs) have no packet form"
    if getattr(geometry, "traversal", "") not in ("wide4", "wide8"):
        return f"the {geometry.traversal} traversal has no packet form"
    kinds = set(geometry.kinds)
    if not kinds <= PACKET_KINDS:
        return "primitives of kind " + ", ".join(sorted(kinds - PACKET_KINDS)) + " have no packet test"
    if not set(features.material_kinds) <= PACKET_MATERIALS:
        return "materials of kind " + ", ".join(sorted(set(features.material_kinds) - PACKET_MATERIALS)) + \
            " have no packet form"
    for name, words in _EFFECTS:
        if getattr(features, name):
            return f"no packet form for {words}"
    if textured_emission:
        return "no packet form for textured emission"
    if features.light_kinds:
        return "point, spot and directional lights have no packet form"
    return None
