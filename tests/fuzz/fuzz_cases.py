"""The fuzz test's inputs: seed files, a workspace they are damaged in, and case number -> case.

Case i is fully determined by (SEED, i): which seed file, which damage. The workspace holds copies
of everything the seeds reference, so a damaged model still finds its textures and buffers
inside its own folder, and a damaged scene its environment maps and models.
"""
from __future__ import annotations

import shutil
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tests.fuzz.mutations import mutate
from tests.scene.hostile_inputs import scene_text

REPO = Path(__file__).resolve().parents[2]
DATA = REPO / "tests" / "data"
ASSETS = REPO / "assets"
SEED = 20240611

# Small scenes written here: every operator, a constant and a map environment, a model, the
# analytic shapes; these (and the models) are also rendered when they load.
SMALL_SDF = scene_text(
    '[[objects]]\ntype = "smooth_union"\nmaterial = "white"\nk = 0.2\n'
    '[[objects.children]]\ntype = "sphere"\nradius = 0.5\n'
    '[[objects.children]]\ntype = "subtraction"\ntranslate = [0.6, 0.0, 0.0]\n'
    '[[objects.children.children]]\ntype = "box"\nsize = [0.6, 0.6, 0.6]\n'
    '[[objects.children.children]]\ntype = "torus"\nmajor_radius = 0.3\nminor_radius = 0.1\n'
    '[[objects]]\ntype = "repeat"\nmaterial = "white"\nperiod = [1.5, 0.0, 1.5]\nlimit = [2, 0, 2]\n'
    '[[objects.children]]\ntype = "capsule"\nheight = 0.3\nradius = 0.1\ntranslate = [0.0, -1.0, 0.0]\n'
    '[[objects]]\ntype = "plane"\nmaterial = "white"\noffset = -1.2\n')
SMALL_MESH = scene_text(
    '[[objects]]\ntype = "mesh"\nfile = "../data/textured_quad.gltf"\n'
    '[[objects]]\ntype = "sphere"\nmaterial = "white"\nradius = 0.3\ntranslate = [1.0, 0.0, 0.0]\n'
    '[[objects]]\ntype = "quad"\nmaterial = "white"\nsize = [4.0, 4.0]\ntranslate = [0.0, -1.0, 0.0]\n',
    geometry="mesh").replace('type = "constant"\ncolor = [0.5, 0.5, 0.5]',
                             'type = "map"\nfile = "../envmaps/venice.exr"')


@dataclass(frozen=True)
class Seed:
    source: Path | None  # the file to damage (None: `text`)
    folder: str  # where the damaged copy goes in the workspace
    name: str  # its file name there
    open_name: str  # the file to open afterwards (an MTL is opened through its OBJ)
    render: bool  # render a tiny image when it loads
    text: str = ""


def seeds() -> list[Seed]:
    models = sorted(DATA.glob("*.gltf")) + [DATA / "textured_quad.glb", DATA / "materials.obj", DATA / "pyramid.ply"]
    out = [Seed(p, "data", f"case{p.suffix}", f"case{p.suffix}", True) for p in models]
    out.append(Seed(DATA / "materials.mtl", "mtl", "materials.mtl", "materials.obj", True))
    out += [Seed(p, "scenes", "case.toml", "case.toml", False) for p in sorted((ASSETS / "scenes").glob("*.toml"))]
    out += [Seed(None, "scenes", "case.toml", "case.toml", True, SMALL_SDF),
            Seed(None, "scenes", "case.toml", "case.toml", True, SMALL_MESH)]
    return out


def make_workspace(root: Path) -> Path:
    """Copies of the test models' files (models refuse references leading out of their folder,
    so they cannot be links), and links to the shipped environment maps and models."""
    (root / "data").mkdir(parents=True)
    for p in DATA.iterdir():
        if p.suffix.lower() in (".png", ".bin", ".mtl", ".gltf", ".obj", ".glb", ".ply"):
            shutil.copy(p, root / "data" / p.name)
    (root / "mtl").mkdir()
    for name in ("materials.obj", "checker.png"):
        shutil.copy(DATA / name, root / "mtl" / name)
    (root / "scenes").mkdir()
    for name in ("envmaps", "models"):
        (root / name).symlink_to(ASSETS / name)
    return root


@dataclass(frozen=True)
class Case:
    index: int
    seed: Seed
    damage: str
    path: Path  # the file to open

    @property
    def origin(self) -> str:
        return self.seed.source.name if self.seed.source else ("small sdf scene" if self.seed.text == SMALL_SDF
                                                               else "small mesh scene")

    @property
    def kind(self) -> str:
        """What reads it: the file format of a model (.gltf, .glb, .obj, .mtl, .ply), or the small scene."""
        return self.seed.source.suffix if self.seed.source else self.origin

    @property
    def label(self) -> str:
        return f"case {self.index}: {self.origin}, {self.damage}"


def write_case(root: Path, index: int) -> Case:
    """Damage the seed file of case `index` and write it into the workspace."""
    rng = np.random.default_rng([SEED, index])
    all_seeds = seeds()
    seed = all_seeds[int(rng.integers(0, len(all_seeds)))]
    data = seed.source.read_bytes() if seed.source else seed.text.encode()
    damaged, damage = mutate(seed.name, data, rng)
    (root / seed.folder / seed.name).write_bytes(damaged)
    return Case(index, seed, damage, root / seed.folder / seed.open_name)
