"""An animation's frames assembled into a video file with imageio's ffmpeg plugin (H.264, the
ffmpeg binary that the imageio-ffmpeg package ships)."""
from __future__ import annotations

from pathlib import Path
from typing import Iterable

import numpy as np

from renderer.output.atomic_write import atomic_output
from renderer.commands.headless import check_writable

# Containers that take H.264 video as ffmpeg writes it by default.
VIDEO_EXTENSIONS = (".mp4", ".mov", ".mkv")


def ffmpeg_unavailable() -> str | None:
    """Why no video can be written here (one line), or None."""
    try:
        import imageio_ffmpeg
    except ImportError:
        return "the imageio-ffmpeg package is not installed (pip install imageio-ffmpeg)"
    try:
        imageio_ffmpeg.get_ffmpeg_exe()
    except RuntimeError as error:
        return f"no ffmpeg executable found ({' '.join(str(error).split())})"
    return None


def check_video_path(path: Path) -> None:
    """A one-line ValueError unless a video can be written at `path` (before anything renders)."""
    if path.suffix.lower() not in VIDEO_EXTENSIONS:
        raise ValueError(f"{path}: unsupported video extension '{path.suffix}' (use "
                         f"{', '.join(VIDEO_EXTENSIONS[:-1])} or {VIDEO_EXTENSIONS[-1]})")
    check_writable(path)
    reason = ffmpeg_unavailable()
    if reason:
        raise ValueError(f"{path}: cannot write a video: {reason}")


def even_sized(rgb: np.ndarray) -> np.ndarray:
    """H.264 in yuv420p needs an even width and height: an odd one gets its last row or column
    repeated (rather than the whole frame resampled)."""
    height, width = rgb.shape[:2]
    return np.pad(rgb, ((0, height % 2), (0, width % 2), (0, 0)), mode="edge")


def write_video(path: Path, frames: Iterable[np.ndarray], fps: float) -> int:
    """Display frames (H, W, 3) uint8 to `path` at `fps`; the number of frames written."""
    import imageio.v2 as imageio

    count = 0
    try:
        with atomic_output(path) as temporary:
            writer = imageio.get_writer(temporary, format="FFMPEG", mode="I", fps=fps, codec="libx264",
                                        pixelformat="yuv420p", macro_block_size=2, ffmpeg_log_level="error")
            try:
                for frame in frames:
                    writer.append_data(even_sized(frame))
                    count += 1
            finally:
                writer.close()
    except (OSError, RuntimeError) as error:
        raise RuntimeError(f"{path}: writing the video failed: {' '.join(str(error).split())}") from None
    return count
