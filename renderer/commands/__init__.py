"""The commands behind app.py that render to files.

render.py             `app.py render`: options to files, checkpoints, resumption, a clean stop
headless.py           the headless render loop with its progress bar
interrupts.py         Ctrl-C and SIGTERM during a render
animation/            `render --turntable` / `--camera-path`: frames, videos
distributed/          renders and animations spread over Ray workers
"""
