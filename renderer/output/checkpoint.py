"""Render checkpoints: a film's exact state and what defines the render, in one file.

A checkpoint is a numpy .npz archive (a zip of .npy arrays: no pickles, readable with nothing but
numpy) holding the film's four arrays (FilmState: mean, Welford m2, sample and rejected counts,
float32 / int32 exactly as the device held them) and `header`, a JSON text with the render's
definition (CheckpointHeader). It is written atomically (renderer/output/atomic_write.py), so an
interrupted save leaves the previous checkpoint whole.

Continuing from it is bit for bit the render that never stopped: samples are hashes of (pixel,
sample index, dimension, seed), each pixel continues at its own sample index (its counts), the
round of pixel slices continues at `slices_in_round`, and the film resumes from the same float32
values (see FilmState).
"""
from __future__ import annotations

import hashlib
import json
import os
import zipfile
from dataclasses import MISSING, asdict, dataclass, fields
from pathlib import Path
from urllib.parse import unquote

import numpy as np

from renderer.film.adaptive import DEFAULT_MIN_SPP
from renderer.output.atomic_write import atomic_output
from renderer.film.accumulation import FilmState
from renderer.scene.errors import SceneError
from renderer.scene.description import Scene

# The layout of the archive; a reader refuses others. 2: the position in a round of pixel slices;
# 3: adaptive sampling's state and the denoising AOVs (optional arrays), their options; 4: a
# round's slices past its first 64 are rows of each cell (pixel_slices.rank_matrix), so a
# position within a round names other pixels than in format 3.
FORMAT = 4
CHECKPOINT_EXTENSION = ".ckpt"
HEADER = "header"
INTEGER_FIELDS = ("width", "height", "seed", "max_depth", "spp_done", "slices_in_round", "min_spp")


@dataclass
class CheckpointHeader:
    lantern_version: str
    scene: str  # the scene (or model) file, absolute
    scene_hash: str  # scene_fingerprint(): the scene file and every file it reads
    width: int
    height: int
    integrator: str
    sampler: str
    seed: int
    max_depth: int
    spp_done: int  # samples every pixel has
    slices_in_round: int  # pixel slices of the next sample already rendered (renderer/film/pixel_slices.py)
    spp_target: int | None  # None: a --time budget
    seconds_budget: float | None
    seconds_rendered: float  # rendering time so far (a --time budget continues from it)
    arch: str  # the back-end it ran on (bit-identity holds on the same back-end and optimisation)
    optimize: str
    out: str
    variance: str | None
    exposure: float
    tonemapper: str | None
    automatic: bool  # a default checkpoint beside --out: removed when the render completes
    denoise: bool = False
    aovs: bool = False
    noise_threshold: float | None = None  # adaptive sampling (None: uniform)
    min_spp: int = DEFAULT_MIN_SPP
    # Ray workers of a distributed render (renderer/commands/distributed/): its pixel groups may stand at
    # different sample counts, so it continues distributed (with any number of workers). None: one process.
    workers: int | None = None
    packets: int = 0  # rays a packet (render --packets; 0: one at a time): a resume continues alike
    format: int = FORMAT

    def mismatches(self, other: "CheckpointHeader") -> list[str]:
        """What of `other`'s render definition differs from this checkpoint's, in words."""
        problems = []
        if other.lantern_version != self.lantern_version:
            problems.append(f"written by Lantern {self.lantern_version}, this is Lantern {other.lantern_version}")
        if other.scene_hash != self.scene_hash:
            if Path(other.scene) == Path(self.scene):
                problems.append(f"the scene {other.scene} (a file it reads, or its -D parameters) has changed since "
                                "the checkpoint")
            else:
                problems.append(f"the scene {other.scene} is not the checkpoint's ({self.scene})")
        if (other.width, other.height) != (self.width, self.height):
            problems.append(f"size {other.width}x{other.height} differs from the checkpoint's {self.width}x{self.height}")
        for name in ("integrator", "sampler", "seed", "max_depth"):
            mine, theirs = getattr(self, name), getattr(other, name)
            if mine != theirs:
                problems.append(f"{name.replace('_', ' ')} {theirs} differs from the checkpoint's {mine}")
        return problems


def save_checkpoint(path: str | os.PathLike, header: CheckpointHeader, state: FilmState) -> None:
    text = json.dumps(asdict(header), sort_keys=True)
    with atomic_output(path) as temporary, open(temporary, "wb") as f:
        # A file object: given a name, np.savez would append ".npz" to it.
        arrays = {name: getattr(state, name) for name, _, _ in FilmState.ARRAYS + FilmState.OPTIONAL_ARRAYS
                  if getattr(state, name) is not None}
        np.savez(f, **{HEADER: np.array(text)}, **arrays)


def read_header(path: str | os.PathLike) -> CheckpointHeader:
    """The header alone (the arrays stay on disk); a one-line SceneError for anything unreadable."""
    with _open(path) as archive:
        return _header(path, archive)


def load_checkpoint(path: str | os.PathLike) -> tuple[CheckpointHeader, FilmState]:
    with _open(path) as archive:
        header = _header(path, archive)
        try:
            arrays = {name: archive[name] for name, _, _ in FilmState.ARRAYS}
            arrays.update({name: archive[name] for name, _, _ in FilmState.OPTIONAL_ARRAYS if name in archive.files})
        except (KeyError, ValueError, OSError, zipfile.BadZipFile) as error:
            raise SceneError(path, f"not a complete Lantern checkpoint ({_one_line(error)})") from None
    state = FilmState(**arrays)
    problem = state.problem()
    if problem:
        raise SceneError(path, f"corrupt checkpoint: {problem}")
    if state.size != (header.width, header.height):
        raise SceneError(path, f"corrupt checkpoint: film {state.size[0]}x{state.size[1]}, header "
                               f"{header.width}x{header.height}")
    return header, state


def is_checkpoint(path: str | os.PathLike) -> bool:
    """Whether `path` is a Lantern checkpoint of any format (a zip archive whose header names a
    Lantern version): what a new checkpoint may replace. Reads the header alone."""
    try:
        with zipfile.ZipFile(path) as archive:
            if f"{HEADER}.npy" not in archive.namelist():
                return False
        with np.load(path, allow_pickle=False) as arrays:
            values = json.loads(str(arrays[HEADER]))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return False
    return isinstance(values, dict) and "lantern_version" in values


def _open(path):
    if not Path(path).is_file():
        raise SceneError(path, "checkpoint not found")
    try:
        return np.load(path, allow_pickle=False)
    except (ValueError, OSError, zipfile.BadZipFile, EOFError) as error:
        raise SceneError(path, f"not a Lantern checkpoint ({_one_line(error)})") from None


def _header(path, archive) -> CheckpointHeader:
    try:
        values = json.loads(str(archive[HEADER]))
    except (KeyError, ValueError, OSError, zipfile.BadZipFile) as error:
        raise SceneError(path, f"not a Lantern checkpoint (no readable header: {_one_line(error)})") from None
    if not isinstance(values, dict) or values.get("format") != FORMAT:
        found = values.get("format") if isinstance(values, dict) else None
        raise SceneError(path, f"checkpoint format {found} is not the format this Lantern reads ({FORMAT})")
    names = {f.name for f in fields(CheckpointHeader)}
    optional = {f.name for f in fields(CheckpointHeader) if f.default is not MISSING}
    missing = sorted(names - optional - set(values))
    if missing:
        raise SceneError(path, f"corrupt checkpoint header: missing {', '.join(missing)}")
    wrong = [name for name in INTEGER_FIELDS if not isinstance(values[name], int) or isinstance(values[name], bool)]
    if wrong:
        raise SceneError(path, f"corrupt checkpoint header: {', '.join(wrong)} not an integer")
    return CheckpointHeader(**{k: v for k, v in values.items() if k in names})


# --- what defines the scene ------------------------------------------------------------------------

def scene_files(scene: Scene) -> list[Path]:
    """The files a render of `scene` reads: the scene file and what its reader read besides (a Mitsuba
    scene's includes), its environment map, its materials' and lights' textures, its media's grids, its model
    files, the buffers and images a .gltf names beside it and an .obj's material libraries and textures."""
    found = [scene.path, *scene.source_files, scene.environment.file if scene.environment.kind == "map" else None]
    found += [t.file for m in scene.materials for t in m.textures.values() if t.file is not None]
    found += [light.texture.file for light in scene.lights if light.texture is not None and light.texture.file]
    found += [grid.file for m in scene.media for grid in (m.density, m.albedo) if grid is not None and grid.file]
    for obj in scene.mesh_objects:
        if obj.file is not None:
            found.append(obj.file)
            if Path(obj.file).suffix.lower() == ".gltf":
                found.extend(_gltf_resources(Path(obj.file)))
            elif Path(obj.file).suffix.lower() == ".obj":
                from renderer.scene.model_formats.obj_mtl import obj_dependencies

                found.extend(obj_dependencies(Path(obj.file)))
    unique = []
    for path in found:
        if path is not None and Path(path).resolve() not in unique:
            unique.append(Path(path).resolve())
    return unique


def scene_fingerprint(scene: Scene) -> str:
    """SHA-256 over the contents of scene_files() (in order; a moved scene keeps its print) and the
    parameters the scene was read with (a Mitsuba scene's -D)."""
    digest = hashlib.sha256()
    for name, value in scene.parameters:
        digest.update(f"{name}={value}\0".encode())
    for path in scene_files(scene):
        file_digest = hashlib.sha256()
        with open(path, "rb") as f:
            for block in iter(lambda: f.read(1 << 20), b""):
                file_digest.update(block)
        digest.update(file_digest.digest())
    return digest.hexdigest()


def _gltf_resources(path: Path) -> list[Path]:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []  # the loader has reported (or will report) the file itself
    uris = [item.get("uri") for key in ("buffers", "images") for item in document.get(key, ()) if isinstance(item, dict)]
    return [path.parent / unquote(uri) for uri in uris
            if isinstance(uri, str) and not uri.startswith("data:") and (path.parent / unquote(uri)).is_file()]


def _one_line(error: Exception) -> str:
    text = str(error).strip().splitlines()
    return text[0] if text else type(error).__name__
