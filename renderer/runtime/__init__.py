"""The Taichi runtime: start-up, back-end choice, uploads, memory and optimisation level.

arch.py               Taichi initialisation from an entry point (never at import time), options
taichi_frontend.py    cheaper kernel compiles (two costs of Taichi's Python front end)
upload.py             many numpy arrays into Taichi fields with one launch
allocation.py         how large per-pixel fields are for an image (no Taichi: budgets use it)
optimize_choice.py    which optimisation level a `render` compiles with
version.py            Lantern's version
"""
