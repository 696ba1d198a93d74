"""How large per-pixel fields are allocated for an image (no Taichi here: memory budgets use it too)."""

# Per-pixel fields are allocated in whole steps of this many pixels each way. Compiled code depends
# on the shapes of the fields a kernel touches (the offline cache keys kernels by them): with exact
# sizes, the same scene rendered at 64x36 and at 128x72, or a window resized by a pixel, compiled
# every program again (13 s cold against 4.7 s from the cache, the textured scene's mis kernel).
# Within a step they share their programs. The extra memory is under a step's width of rows and
# columns (1920x1080 allocates 1920x1088).
ALLOCATION_STEP = 64


def allocation_size(width: int, height: int) -> tuple[int, int]:
    """The field shape that holds a width x height image: each side rounded up to ALLOCATION_STEP."""
    return (-(-width // ALLOCATION_STEP) * ALLOCATION_STEP, -(-height // ALLOCATION_STEP) * ALLOCATION_STEP)
