"""Copy many numpy arrays into Taichi fields with one kernel launch.

`field.from_numpy` compiles (or loads from the offline cache and JIT-compiles) a copy kernel for
every field it is called on, ~8 ms each even warm: a scene that uploads 30 fields spends a
quarter of a second of its start-up there. `upload_fields` packs the arrays into one f32 and one
i32 buffer and scatters them with a single kernel specialised to the whole set.
"""

import numpy as np
import taichi as ti

_KINDS = {ti.f32: (np.float32, 0), ti.i32: (np.int32, 1)}


def _element_shape(field) -> tuple[int, ...]:
    """The trailing array axes of one element, as from_numpy/to_numpy lay them out."""
    if not hasattr(field, "n"):
        return ()
    return (field.n,) if field.m == 1 else (field.n, field.m)


def _cell_count(field) -> int:
    return int(np.prod(field.shape, dtype=np.int64))


@ti.func
def _multi_index(local, shape):
    """The row-major multi-index of flat cell `local` in a field of `shape` (compile-time)."""
    index = ti.Vector([0] * ti.static(len(shape)), dt=ti.i32)
    rest = local
    for d in ti.static(range(len(shape) - 1, -1, -1)):
        index[d] = rest % shape[d]
        rest = rest // shape[d]
    return index


UNROLL_GROUP = 32  # Taichi warns above 32 unrolled iterations in one loop


@ti.func
def _store(field: ti.template(), I, value_base, element: ti.template(), buffer: ti.template()):
    # A vector or matrix element is stored whole: stored component by component, Taichi 1.7.4's
    # optimised CPU code crashed for some sets of fields (wide BVH node bounds (M, 6) vec4, child
    # references (M, 4) i32, then any vec4 f32 field, in that order; right under debug=True).
    if ti.static(element == ()):
        field[I] = buffer[value_base]
    elif ti.static(len(element) == 1):
        field[I] = ti.Vector([buffer[value_base + c] for c in ti.static(range(element[0]))])
    else:
        field[I] = ti.Matrix([[buffer[value_base + r * element[1] + c] for c in ti.static(range(element[1]))]
                              for r in ti.static(range(element[0]))])


@ti.kernel
def _scatter(targets: ti.template(), cells: ti.i32, f32: ti.types.ndarray(dtype=ti.f32, ndim=1),
             i32: ti.types.ndarray(dtype=ti.i32, ndim=1)):
    # targets: ((field, first cell, value offset, width, kind, element shape), ...), compile-time
    # constants. One flat loop over every cell of every field: one parallel task, not one per
    # field (each task costs compile and load time).
    for cell in range(cells):
        # Unrolled in groups of UNROLL_GROUP: the same code, each loop under Taichi's unrolling limit.
        for g in ti.static(range(0, len(targets), UNROLL_GROUP)):
            for k in ti.static(range(g, min(g + UNROLL_GROUP, len(targets)))):
                field, first, offset, width, kind, element = ti.static(targets[k])
                if first <= cell and cell < first + ti.static(_cell_count(field)):
                    local = cell - first
                    buffer = ti.static(f32 if kind == 0 else i32)
                    if ti.static(len(field.shape) == 1):  # most fields: the cell is the index
                        _store(field, local, offset + local * width, element, buffer)
                    else:
                        _store(field, _multi_index(local, ti.static(field.shape)), offset + local * width, element,
                               buffer)


def _members(pairs):
    """(field, array) pairs with each struct field expanded into its members (its array: a dict
    of member name -> array, as StructField.from_numpy takes)."""
    for field, array in pairs:
        if hasattr(field, "get_member_field"):
            for name in field.keys:
                yield from _members([(field.get_member_field(name), array[name])])
        else:
            yield field, array


def upload_fields(pairs) -> None:
    """Copy each (field, array) pair, as `field.from_numpy(array)` would, in one kernel launch.

    Fields of f32 or i32 elements (scalars, vectors or matrices) and struct fields of them (with a
    dict of arrays); an array must have the field's shape followed by its element shape. Other
    element types fall back to from_numpy.
    """
    targets, f32_parts, i32_parts = [], [], []
    sizes = [0, 0]
    cells = 0
    for field, array in _members(pairs):
        array = np.asarray(array)
        element = _element_shape(field)
        if array.shape != tuple(field.shape) + element:
            raise ValueError(f"upload: array of shape {array.shape} for a field of shape {tuple(field.shape)} "
                             f"with elements {element}")
        if field.dtype not in _KINDS:
            field.from_numpy(array)
            continue
        np_type, kind = _KINDS[field.dtype]
        width = int(np.prod(element, dtype=np.int64))
        targets.append((field, cells, sizes[kind], width, kind, element))
        cells += _cell_count(field)
        (f32_parts, i32_parts)[kind].append(np.ascontiguousarray(array, np_type).reshape(-1))
        sizes[kind] += array.size
    if not targets:
        return
    f32 = np.concatenate(f32_parts) if f32_parts else np.zeros(1, np.float32)
    i32 = np.concatenate(i32_parts) if i32_parts else np.zeros(1, np.int32)
    _scatter(tuple(targets), cells, f32, i32)
