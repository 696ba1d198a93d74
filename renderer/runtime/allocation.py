"""How large per-pixel fields are allocated for an image (no Taichi here: memory budgets use it too)."""

# Per-pixel fields are allocated in whole steps of this many pixels each way. Compiled code depends
# on the shapes of the fields a kernel touches (the offline cache keys kernels by them): with exact
# sizes, the same scene at another size, or a window resized by a pixel, compiled every program
# again. Within a step they share their programs: the textured scene's first mis render at 48x27
# took 16.6 s on a clean cache, then at 64x36 (the same 64x64 allocation) 4.2 s. The extra memory is under a step's width of rows and
# columns (1920x1080 allocates 1920x1088).
ALLOCATION_STEP = 64


def allocation_size(width: int, height: int) -> tuple[int, int]:
    """The field shape that holds a width x height image: each side rounded up to ALLOCATION_STEP."""
    if width < 1 or height < 1:
        raise ValueError(f"image size must be positive, got {width}x{height}")
    return (-(-width // ALLOCATION_STEP) * ALLOCATION_STEP, -(-height // ALLOCATION_STEP) * ALLOCATION_STEP)
