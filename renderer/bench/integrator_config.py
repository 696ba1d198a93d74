"""What `bench integrators` measures: its scenes, integrators, samplers, sizes and budgets, full and
quick (renderer/bench/integrators.py describes the measurement)."""
from __future__ import annotations

from dataclasses import dataclass

INTEGRATORS = ("path", "nee", "mis")
SAMPLERS = ("independent", "sobol")
SCENES = ("cornell_box", "bunnies", "studio", "many_lights")
MITSUBA_SCENE = "cornell_box"
MITSUBA_LD_SAMPLER = "multijitter"  # Mitsuba's best at equal time here (vs stratified, ldsampler, orthogonal)
# Rows whose spp to the targets is measured over seeds (the best samplers; see step 4)
SEEDED_ROWS = ("mis/sobol", "nee/sobol", f"mitsuba/{MITSUBA_LD_SAMPLER}")
METRICS = ("rmse", "rel_mse", "rel_mse_trimmed")


@dataclass(frozen=True)
class IntegratorBenchConfig:
    square_size: tuple[int, int] = (128, 128)  # scenes with a square image (the Cornell box)
    wide_size: tuple[int, int] = (160, 90)  # every other scene
    budget_s: float = 10.0  # render time per (integrator, sampler) curve: the equal-time budget
    reference_s: float = 60.0  # render time of each scene's reference
    reference_launch_s: float = 3.0  # longest single launch while rendering the reference
    max_spp: int = 1 << 16  # curves stop here even within the budget
    seed: int = 1  # test images (one seed for every integrator and sampler)
    reference_seed: int = 104729  # reference: independent of the test seed
    scenes: tuple[str, ...] = SCENES
    integrators: tuple[str, ...] = INTEGRATORS
    samplers: tuple[str, ...] = SAMPLERS
    mitsuba: bool = True
    mitsuba_threads: int = 2
    mitsuba_reference_spp: int = 2048  # rendered in passes of mitsuba_pass_spp (memory: one lane per sample)
    mitsuba_pass_spp: int = 256
    mitsuba_target_spp: int = 64  # the target RMSE is Mitsuba's at this spp
    mitsuba_curve_max_spp: int = 512  # Mitsuba's error curve: 1, 2, 4, ... spp, each a separate render
    mitsuba_target_renders: int = 8  # round-robin runs (seeds) of the equal-spp comparison
    seeded_renders: int = 16  # seeds per spp level of the best samplers' error (SEEDED_ROWS)
    seeded_max_spp: int = 128  # highest spp level of that measurement
    # Whole-process time (renderer/bench/whole_process.py): both commands, start to exit
    whole_process: bool = True
    whole_process_size: int = 256
    whole_process_spp: int = 256
    whole_process_runs: int = 3
    whole_process_reference_spp: int = 1024
    # The mesh-heavy comparison with Mitsuba (renderer/bench/mesh_heavy.py): "full", "quick" or "off"
    mesh_heavy: str = "full"


FULL = IntegratorBenchConfig()
QUICK = IntegratorBenchConfig(square_size=(64, 64), wide_size=(96, 54), budget_s=2.0, reference_s=8.0,
                              reference_launch_s=2.0, mitsuba_reference_spp=1024, mitsuba_pass_spp=256,
                              mitsuba_target_spp=32, mitsuba_curve_max_spp=256, mitsuba_target_renders=8,
                              seeded_renders=6, seeded_max_spp=64,
                              whole_process_size=64, whole_process_spp=64, whole_process_runs=2,
                              whole_process_reference_spp=512, mesh_heavy="quick")
