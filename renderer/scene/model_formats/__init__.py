"""Model files (glTF 2.0 / GLB, OBJ + MTL, PLY, STL, Mitsuba's serialized) read into a `MeshAsset`, one module per format.

`load_mesh_asset(path)` (load.py) is the one entry point. It returns triangle meshes (world-space
ones and instanced ones), PBR materials and images at their own precision (conventions in
`renderer.scene.mesh_model`), or raises a one-line `SceneError` naming the file and the problem.

- load.py: the entry point, choosing a reader by the file's extension
- gltf.py, obj_mtl.py, ply_stl.py, serialized.py: how each format is read (each module's notes say
  what is kept)
- builder.py: what every format shares: materials, images, validation, placement and bounds
- image_decoding.py: texture images decoded at their own precision, their sizes from headers
- normals.py, tangents.py: vertex normals and tangents generated where a file lacks them
- mesh_warnings.py: the warnings a model that still loads can raise
- gltf_writing.py: the other direction, glTF written by the project's model generators

Checks (all formats)
--------------------
SceneError: missing file, unsupported extension, unreadable or truncated data, no triangles at
all, non-finite positions / UVs / colours, vertex indices out of range, a missing buffer or
material library file, an image that does not decode, a required glTF extension we do not
implement, a glTF node reached twice (a cycle, or a node with two parents), and any other
failure inside a reader (trimesh's included), always in one line naming the model file.
Memory: what the file declares is charged to the scene's `MemoryLedger` (renderer.scene.limits)
before it is allocated: the file itself, external buffers, each accessor's count (8 bytes a
component, with or without a bufferView, sparse ones too), each mesh build (MESH_BUILD_* and
TANGENT_* bytes per vertex and triangle), trimesh's parsing (TRIMESH_PARSE_BYTES_PER_BYTE) and each
image from its header (its texels kept IMAGE_COPIES times, its decoding's peak); what would pass
the budget is refused, naming what, how much and the limit.
References: glTF URIs, OBJ `mtllib` and texture maps and a PLY `TextureFile` are resolved with
symlinks followed and must lie inside the model's folder, unless `LoadOptions.allow_outside_files`.
Warning (`MeshWarning`, one line naming the model file): a missing texture file (one warning per
file, naming the materials that use it; they keep their factors alone, as other viewers do),
glTF extensions used but not implemented.
Warning (`DegenerateTrianglesWarning`, one per file with the count): triangles with a repeated
vertex index or zero area are removed. "Zero area" is tested in float64 on the world-space
positions (local ones for instanced meshes), relative to the triangle's size: twice the area
below 1e-12 times the squared longest edge (height < 1e-12 of its length). Normals are
transformed with the cofactor matrix of the node transform (det(M) times the inverse transpose:
the same directions, and still defined when a zero scale flattens the model;
`mesh_model.normal_matrix`). Normals that are zero or non-finite are replaced by the
area-weighted average of the adjacent face normals (`MeshWarning`).
"""
from renderer.scene.model_formats.load import MESH_EXTENSIONS, load_mesh_asset
from renderer.scene.model_formats.mesh_warnings import DegenerateTrianglesWarning, MeshWarning

__all__ = ["MESH_EXTENSIONS", "load_mesh_asset", "MeshWarning", "DegenerateTrianglesWarning"]


