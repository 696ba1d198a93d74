"""Distributed renders on Ray: a still's pixels cut into groups whose samples are rendered in chunks by
Ray actors, each with its own Taichi runtime, and merged into one film bit for bit.

pixel_slices.py already makes a pixel's samples depend only on the pixel and its own sample index,
so a group of pixel slices can be rendered anywhere, in any number of chunks, and end exactly as in
one process. Modules: pixel_groups.py (which pixels a chunk covers, their state in and out of a
film), planner.py (which chunk next: pure logic), bundle.py (the scene's files shipped to other
machines), worker.py (the actor), cluster.py (starting or joining Ray), render.py (the driver loop),
frames.py (animation frames as tasks).
"""
