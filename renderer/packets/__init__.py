"""Packets of rays on the CPU: several paths a loop index, one a lane of Taichi vectors, so that
LLVM's vectoriser runs them side by side (Taichi never vectorises across loop indices).

lanes.py       lane arithmetic: masks, selects, polynomial sine and cosine, frames, ray offsets
primitives.py  one triangle (watertight), quad or sphere against every ray of a packet
traversal.py   a packet through the wide BVH together (shared stack, any ray entering a child)
records.py     every primitive as three vec4 rows, for branch-free gathers per lane
surfaces.py    hit points, normals, clearances and materials of a packet's hits
lights.py      light samples for a packet (emitters by power, a constant environment)
path.py        path / nee / mis for a packet of camera rays
program.py     PacketProgram: RenderProgram's launch contract, a pass's neighbouring pixels a packet
support.py     which scenes and integrators the packet path takes (and why not)

Taken where MeshOptions.packets (`render --packets N`) asks and support.py admits the scene;
everything else renders one ray at a time as before. docs/findings.md ("Packets of rays") has
what it gains and costs today.
"""
