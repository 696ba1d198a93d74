"""renderer.runtime.upload: one launch copies many arrays into fields exactly as from_numpy would."""
import numpy as np
import pytest
import taichi as ti

from renderer.runtime.upload import upload_fields


def test_every_element_kind_lands_where_from_numpy_puts_it():
    rng = np.random.default_rng(3)
    record = ti.types.struct(a=ti.f32, b=ti.math.vec3, c=ti.i32)
    pairs = [
        (ti.Vector.field(3, ti.f32, shape=(4, 3)), rng.random((4, 3, 3))),
        (ti.field(ti.i32, shape=5), rng.integers(-100, 100, 5)),
        (ti.Matrix.field(2, 3, ti.f32, shape=2), rng.random((2, 2, 3))),
        (ti.field(ti.f32, shape=(3, 2)), rng.random((3, 2))),
        (ti.Vector.field(3, ti.i32, shape=7), rng.integers(0, 1 << 30, (7, 3))),
        (ti.Vector.field(2, ti.f32, shape=(2, 3, 2)), rng.random((2, 3, 2, 2))),
    ]
    struct = record.field(shape=4)
    struct_arrays = {"a": rng.random(4), "b": rng.random((4, 3)), "c": np.arange(4) * 7}
    upload_fields(pairs + [(struct, struct_arrays)])
    for field, array in pairs:
        expected = field.to_numpy()  # for its dtype
        np.testing.assert_array_equal(field.to_numpy(), array.astype(expected.dtype))
    got = struct.to_numpy()
    for name, array in struct_arrays.items():
        np.testing.assert_array_equal(got[name], array.astype(got[name].dtype))


def test_wide_node_fields_then_packet_rows_in_one_launch():
    """The set of fields on which component-by-component stores crashed Taichi 1.7.4's optimised
    CPU code (a wide BVH's node bounds and child references, then a packet's corner rows): copied
    exactly, in this order, in one launch."""
    rng = np.random.default_rng(5)
    pairs = [(ti.Vector.field(4, ti.f32, shape=(238, 6)), rng.random((238, 6, 4))),
             (ti.field(ti.i32, shape=(238, 4)), rng.integers(-1000, 1000, (238, 4))),
             (ti.Vector.field(4, ti.f32, shape=(320, 9)), rng.random((320, 9, 4))),
             (ti.Vector.field(4, ti.i32, shape=320), rng.integers(-1, 1000, (320, 4)))]
    upload_fields(pairs)
    for field, array in pairs:
        np.testing.assert_array_equal(field.to_numpy(), array.astype(field.to_numpy().dtype))


def test_wrong_shape_is_refused():
    field = ti.Vector.field(3, ti.f32, shape=4)
    with pytest.raises(ValueError, match="shape"):
        upload_fields([(field, np.zeros((4, 2)))])


def test_same_fields_again_reuse_the_kernel_and_overwrite():
    field = ti.field(ti.f32, shape=3)
    upload_fields([(field, np.array([1.0, 2.0, 3.0]))])
    upload_fields([(field, np.array([4.0, 5.0, 6.0]))])
    np.testing.assert_array_equal(field.to_numpy(), [4.0, 5.0, 6.0])
