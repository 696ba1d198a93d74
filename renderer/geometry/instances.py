"""The instances of a mesh scene on the device: where each one's tree starts and its two frames.

Per instance: the root node of its mesh's tree (renderer/geometry/instance_bvh.py) and the 3x4
object-to-world and world-to-object matrices, 100 bytes. Rays enter an object's frame with
world-to-object; a direction is transformed without normalising, so that distances along the
ray (t) stay the world's and hits in different frames compare directly. Hit records go back
with object-to-world: points by the matrix, normals by the inverse transpose (the transpose of
world-to-object), tangents by the matrix; a mirroring instance (det < 0) flips the side its
triangles' winding calls the front, and the tangents' handedness, as renderer/scene/mesh_model.py
prescribes for world meshes.
"""
import numpy as np
import taichi as ti

vec3 = ti.math.vec3
vec4 = ti.math.vec4


def world_to_object(to_world: np.ndarray) -> np.ndarray:
    """(I, 3, 4) inverses of affine (I, 3, 4) matrices (float64)."""
    inv = np.linalg.inv(to_world[:, :, :3])
    return np.concatenate([inv, -np.einsum("nij,nj->ni", inv, to_world[:, :, 3])[:, :, None]], axis=2)


@ti.data_oriented
class InstanceTable:
    BYTES_PER_INSTANCE = 2 * 12 * 4 + 4

    def __init__(self, root: np.ndarray, to_world: np.ndarray, uploads: list):
        """root: (I,) node index of each instance's mesh tree; to_world: (I, 3, 4) float64.
        Appends its (field, array) pairs to `uploads` (one launch for the whole mesh)."""
        n = len(root)
        self.count = n
        self.root = ti.field(ti.i32, shape=n)
        self.to_world = ti.Vector.field(4, ti.f32, shape=(n, 3))  # rows of the 3x4 matrix
        self.to_object = ti.Vector.field(4, ti.f32, shape=(n, 3))
        uploads += [(self.root, root.astype(np.int32)), (self.to_world, to_world.astype(np.float32)),
                    (self.to_object, world_to_object(to_world).astype(np.float32))]

    def device_bytes(self) -> int:
        return self.count * self.BYTES_PER_INSTANCE

    @ti.func
    def ray_to_object(self, i, o, d):
        """(origin, direction) in instance i's frame; the direction keeps its length there."""
        r0, r1, r2 = self.to_object[i, 0], self.to_object[i, 1], self.to_object[i, 2]
        return (vec3(r0.xyz.dot(o) + r0.w, r1.xyz.dot(o) + r1.w, r2.xyz.dot(o) + r2.w),
                vec3(r0.xyz.dot(d), r1.xyz.dot(d), r2.xyz.dot(d)))

    @ti.func
    def point_to_world(self, i, p):
        r0, r1, r2 = self.to_world[i, 0], self.to_world[i, 1], self.to_world[i, 2]
        return vec3(r0.xyz.dot(p) + r0.w, r1.xyz.dot(p) + r1.w, r2.xyz.dot(p) + r2.w)

    @ti.func
    def vector_to_world(self, i, v):
        return vec3(self.to_world[i, 0].xyz.dot(v), self.to_world[i, 1].xyz.dot(v), self.to_world[i, 2].xyz.dot(v))

    @ti.func
    def normal_to_world(self, i, n):
        """The inverse transpose applied to n, normalised (a zero normal stays zero: "none")."""
        w = self.to_object[i, 0].xyz * n.x + self.to_object[i, 1].xyz * n.y + self.to_object[i, 2].xyz * n.z
        length = w.norm()
        return w / length if length > 0.0 else w

    @ti.func
    def tangent_to_world(self, i, t, n):
        """A corner's tangent (xyz, handedness w) in the world, made orthogonal to the corner's
        world normal n (zero: none) and of unit length; w flips under a mirroring instance."""
        w = self.vector_to_world(i, t.xyz)
        w -= n * n.dot(w)
        length = w.norm()
        w = w / length if length > 0.0 else w
        return vec4(w, -t.w if self.mirrored(i) else t.w)

    @ti.func
    def mirrored(self, i):
        r0, r1, r2 = self.to_world[i, 0].xyz, self.to_world[i, 1].xyz, self.to_world[i, 2].xyz
        return r0.dot(r1.cross(r2)) < 0.0
