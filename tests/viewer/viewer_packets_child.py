"""The viewer with packets in a process of its own (a window of its own, as `app.py view
--packets 8` has): `python -m tests.viewer.viewer_packets_child OUT`. Opens the Cornell box
off-screen, renders still frames to at least SPP samples a pixel, then moving frames, then shows
the textured scene; writes the film's mean and variance, what the frames ran and the HUD's lines
to OUT (.npz)."""
import sys

import numpy as np

SIZE = (128, 72)
SPP = 48


def main(out: str) -> None:
    from renderer.runtime.arch import init_taichi

    init_taichi("cpu")
    from renderer.packets.program import PacketProgram
    from renderer.scene.catalog import resolve_scene
    from viewer import hud
    from viewer.window import FrameInput, ViewerApp

    app = ViewerApp(resolve_scene("cornell_box"), size=SIZE, show_window=False, settle_seconds=0.0,
                    still_present_interval=0.0, packets=8)

    def program():
        r = app.renderer
        return r.program(app.session.integrator, r.features(app._camera_frame()), r.scene.render.sampler)

    for _ in range(4000):
        if app.renderer.samples_done >= SPP:
            break
        app.step()
    r = app.renderer
    still = program()
    results = {"mean": r.image(), "variance": r.film.variance_of_mean_image(), "spp": r.samples_done,
               "integrator": app.session.integrator, "still_packets": isinstance(still, PacketProgram),
               "still_traces": still.occupancy()["closest_traces"] if isinstance(still, PacketProgram) else 0,
               "cornell_hud": "\n".join(hud.hud_lines(app.hud_stats()))}
    still.reset_occupancy()
    for _ in range(6):
        app.step(FrameInput(held=frozenset({"w"})))
    results["moving_interactive"] = bool(app.last_plan.interactive)
    results["moving_traces"] = still.occupancy()["closest_traces"]
    results["moving_finite"] = bool(np.isfinite(app.renderer.image()).all())
    app.select_scene(resolve_scene("textured"))
    for _ in range(4):
        app.step()
    results["textured_packets"] = isinstance(program(), PacketProgram)
    results["textured_hud"] = "\n".join(hud.hud_lines(app.hud_stats()))
    np.savez(out, **results)


if __name__ == "__main__":
    main(sys.argv[1])
