"""Animations: `app.py render --frames A:B` (and `--turntable`), a still render per frame.

camera_path.py   a scene's keyframes -> the camera at any time (numpy; C1 Hermite splines)
turntable.py     a camera orbiting the scene's centre about the vertical axis
frame_numbers.py --frames A:B, and the --out pattern (frame_####.png) -> each frame's file
frames.py        FrameRequest / FrameResult and LocalFrames, the frame loop on one Renderer
video.py         the frames written, assembled into a video (imageio's ffmpeg plugin)
command.py       run_animation: options checked before Taichi starts, frames rendered and written
"""
