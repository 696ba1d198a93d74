"""A hashed uniform grid over points, rebuilt on the device every photon pass (SPPM's visible points).

Build (one kernel, its top-level loops run one after another):
  1. clear the per-bucket counts of the `table_size` buckets in use;
  2. count: each point adds 1 to the bucket of its cell (atomic);
  3. exclusive prefix sum of the counts into `start` (blocks of SCAN_BLOCK summed in parallel, the
     block sums scanned serially, then each block written in parallel);
  4. scatter: each point takes the next slot of its bucket (atomic cursor) and writes its id.
The points of bucket h are then entries[start[h] : start[h + 1]].

Cells are cubes of side `cell` (the largest search radius of the pass), indexed from the points'
bounding-box corner; a cell's bucket is a hash of its integer coordinates, modulo the table size (a
power of two near the number of points). A query of radius <= cell around q visits the cells that
overlap the box [q - cell, q + cell], at most 3 per axis (27), and must check that each point it
finds lies in the cell it visits: two of those 27 cells may share a bucket, and a point must not be
found twice. Where points land within a bucket depends on thread scheduling; what a query finds
does not.
"""
import taichi as ti

from renderer.sampling.rng import pcg_hash

vec3 = ti.math.vec3
SCAN_BLOCK = 1024  # buckets summed serially per thread in the prefix sum


def table_size_for(points: int) -> int:
    """The bucket count for `points` points: the power of two at or above it (load factor <= 1)."""
    size = 1
    while size < max(points, 1):
        size *= 2
    return size


@ti.func
def cell_of(p, lo, inv_cell):
    return ti.cast(ti.floor((p - lo) * inv_cell), ti.i32)


@ti.func
def bucket_of(c, mask):
    h = pcg_hash(ti.cast(c.x, ti.u32) ^ pcg_hash(ti.cast(c.y, ti.u32) ^ pcg_hash(ti.cast(c.z, ti.u32))))
    return ti.cast(h & ti.cast(mask, ti.u32), ti.i32)


@ti.data_oriented
class PhotonGrid:
    """The grid's device arrays, sized for up to `capacity` points."""

    def __init__(self, capacity: int):
        self.max_table = table_size_for(capacity)
        self.blocks = max(1, (self.max_table + SCAN_BLOCK - 1) // SCAN_BLOCK)
        self.count = ti.field(ti.i32, shape=self.max_table)
        self.start = ti.field(ti.i32, shape=self.max_table + 1)
        self.block_sum = ti.field(ti.i32, shape=self.blocks)
        self.entries = ti.field(ti.i32, shape=max(1, capacity))

    @ti.func
    def clear(self, table_size):
        for h in range(table_size):
            self.count[h] = 0

    @ti.func
    def scan(self, table_size):
        """start[h] = sum of count[:h] for h <= table_size; count[] is zeroed for the scatter."""
        blocks = (table_size + SCAN_BLOCK - 1) // SCAN_BLOCK
        for b in range(blocks):
            total = 0
            for j in range(SCAN_BLOCK):
                h = b * SCAN_BLOCK + j
                if h < table_size:
                    total += self.count[h]
            self.block_sum[b] = total
        for _ in range(1):  # serial: the block sums, one after another
            acc = 0
            for b in range(blocks):
                t = self.block_sum[b]
                self.block_sum[b] = acc
                acc += t
            self.start[table_size] = acc
        for b in range(blocks):
            acc = self.block_sum[b]
            for j in range(SCAN_BLOCK):
                h = b * SCAN_BLOCK + j
                if h < table_size:
                    self.start[h] = acc
                    acc += self.count[h]
                    self.count[h] = 0
