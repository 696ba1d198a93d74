"""Operators with many children: the children are data, evaluated in a loop; only the shape of the
operator tree is code (shaders_sdf/scene_sdf.py).

A node's shape is its kind, whether its transform is the identity, whether a repetition is finite
and the set of its children's shapes. The number of generated funcs must follow the number of
distinct shapes whatever the number of nodes, and the distances must still be those of the tree:
children combined in file order (a smooth union depends on it), each by its own shape's code.
"""
import time

import numpy as np
import pytest

from renderer.scene import schema
from renderer.scene.description import MaterialSpec
from sdf_helpers import make_geometry, make_scene, node, ref_node, ref_scene, sdf, sdf_material

TOL = 2e-6  # one f32 distance evaluation at |p| <= 3 (tests/sdf/test_primitives.py)


def grid_spheres(count: int, radius: float = 0.04, spacing: float = 0.1, kinds=("sphere",)):
    """`count` small primitives on a square grid in the xz plane (none at the origin: every one has
    a transform), cycling through `kinds`."""
    side = int(np.ceil(np.sqrt(count)))
    children = []
    for i in range(count):
        kind = kinds[i % len(kinds)]
        extra = {"radius": radius} if kind == "sphere" else {"size": (1.6 * radius,) * 3} if kind == "box" else {}
        children.append(node(kind, translate=((i % side - side / 2 + 0.25) * spacing, 0.0, (i // side - side / 2 + 0.25) * spacing),
                             **extra))
    return children


def points_near(objects, count: int, extent: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    p = rng.uniform(-extent, extent, (count, 3))
    p[:, 1] *= 0.2  # most of them close to the grid's plane, where the children are
    return p.astype(np.float32).astype(np.float64)


def assert_matches(geometry, objects, p, tol=TOL):
    got = sdf(geometry, p)
    want = ref_scene(objects, p)
    bound = tol * np.maximum.reduce([np.ones(len(p)), np.linalg.norm(p, axis=1), np.abs(want)])
    worst = int(np.argmax(np.abs(got - want) / bound))
    assert np.all(np.abs(got - want) <= bound), f"at {p[worst]}: got {got[worst]}, want {want[worst]}"


@pytest.mark.parametrize("count", [2, 10, 1000])
def test_code_follows_the_shapes_not_the_children(count):
    program = make_geometry(node("union", *grid_spheres(count))).program
    assert program.node_count == count + 1
    assert program.shape_count == 2  # the union, and a translated sphere
    assert len(program._funcs) == 2


def test_each_distinct_shape_is_generated_once():
    # 300 unions of 20 children of three kinds, under one union: four shapes, 6301 nodes
    inner = [node("union", *grid_spheres(20, kinds=("sphere", "box", "torus")), translate=((k + 1) * 0.01, 0, 0))
             for k in range(300)]
    program = make_geometry(node("union", *inner)).program
    assert program.node_count == 1 + 300 * 21
    assert program.shape_count == 5  # outer union, inner union, sphere, box, torus
    assert len(program._funcs) == 5


def test_ten_thousand_children_compile_quickly_and_match_the_reference():
    """A union of 10,000 spheres (their number never compiled before: 100 took minutes)."""
    objects = (node("union", *grid_spheres(10_000, radius=0.03, spacing=0.07)),)
    start = time.perf_counter()
    geometry = make_geometry(*objects)
    p = points_near(objects, 400, 3.6, seed=1)
    got = sdf(geometry, p)
    seconds = time.perf_counter() - start
    assert seconds < 60, f"{seconds:.0f} s to build and compile"
    want = ref_scene(objects, p)
    assert np.allclose(got, want, atol=TOL * 4)


def test_smooth_union_blends_children_in_file_order():
    """Kinds interleaved (sphere, box, sphere, box...) and blended with a wide k: the polynomial
    smooth minimum is not associative, so evaluating them grouped by kind would differ."""
    children = [node("sphere", radius=0.3, translate=(0.25 * i, 0, 0)) if i % 2 == 0 else
                node("box", size=(0.4, 0.4, 0.4), translate=(0.25 * i, 0.1, 0)) for i in range(12)]
    objects = (node("smooth_union", *children, k=0.5),)
    geometry = make_geometry(*objects)
    p = np.random.default_rng(2).uniform([-0.6, -0.6, -0.6], [3.4, 0.6, 0.6], (20000, 3))
    p = p.astype(np.float32).astype(np.float64)
    assert_matches(geometry, objects, p)
    grouped = (node("smooth_union", *children[0::2], *children[1::2], k=0.5),)
    assert np.abs(ref_scene(grouped, p) - ref_scene(objects, p)).max() > 1e-3  # the order is visible


def test_subtraction_keeps_its_first_child_whatever_the_others_are():
    box = node("box", size=(2.0, 0.6, 0.6))
    cutters = grid_spheres(30, radius=0.12, spacing=0.13, kinds=("sphere", "box"))
    objects = (node("subtraction", box, *cutters, node("box", size=(0.3, 0.3, 0.3), translate=(0.9, 0, 0))),
               node("intersection", node("sphere", radius=1.0, translate=(0, 2, 0)),
                    *[node("sphere", radius=1.0, translate=(0.1 * i, 2.0 + 0.05 * i, 0)) for i in range(20)]))
    geometry = make_geometry(*objects)
    p = np.random.default_rng(3).uniform(-1.5, 3.0, (20000, 3)).astype(np.float32).astype(np.float64)
    assert_matches(geometry, objects, p)


def test_a_finite_repeat_of_a_union_of_many():
    """Repetition folds space into the nearest cell (clamped to the limit) and evaluates the union
    there: compared with that fold done in numpy over the union's reference."""
    cell = node("union", *grid_spheres(40, radius=0.02, spacing=0.05), scale=0.9)
    period, limit, shift = np.array([0.5, 0.0, 0.5]), np.array([2, 0, 2]), np.array([0.0, 0.3, 0.0])
    objects = (node("repeat", cell, period=tuple(period), limit=tuple(limit), translate=tuple(shift)),)
    geometry = make_geometry(*objects)
    p = points_near(objects, 6000, 1.6, seed=4) + shift
    q = p - shift
    index = np.clip(np.round(q / np.where(period > 0, period, 1.0)), -limit, limit)
    want = ref_node(cell, q - np.where(period > 0, period * index, 0.0))
    got = sdf(geometry, p)
    assert np.allclose(got, want, atol=4 * TOL), np.abs(got - want).max()


def test_top_level_trees_of_one_shape_keep_their_materials():
    """300 top-level unions of two spheres share their code; the nearest one's material wins."""
    materials = tuple(MaterialSpec(name) for name in ("a", "b", "c"))
    objects = tuple(node("union", node("sphere", radius=0.05), node("sphere", radius=0.04, translate=(0.06, 0, 0)),
                         translate=((i % 20) * 0.2 - 2, 0, (i // 20) * 0.2 - 1.5), material="abc"[i % 3])
                    for i in range(300))
    geometry = make_geometry(*objects, materials=materials)
    assert geometry.program.shape_count == 3  # the union, its untransformed and its translated sphere
    p = points_near(objects, 5000, 2.2, seed=5)
    d, material = sdf_material(geometry, p)
    each = np.stack([ref_node(o, p) for o in objects])
    nearest = np.argmin(each, axis=0)
    clear = np.sort(each, axis=0)[1] - each.min(axis=0) > 1e-4
    assert np.allclose(d, each.min(axis=0), atol=TOL * 4)
    want = np.array(["abc".index(o.material) for o in objects])[nearest]
    assert np.all(material[clear] == want[clear])
    assert len(np.unique(nearest[clear])) > 250


def deepest_chain(levels: int):
    """Unions nested `levels` deep (a top-level node is level 1), every other level rotated and
    scaled, each holding a small sphere and the next level."""
    tree = node("box", size=(0.1, 0.1, 0.1))
    for level in range(levels - 1, 0, -1):
        transform = dict(rotate=(0, 7.0 * level, 0), scale=1.02) if level % 2 else {}
        tree = node("union", node("sphere", radius=0.05, translate=(0.1 * level, 0, 0)), tree, **transform)
    return tree


def test_the_deepest_allowed_tree_renders_and_matches_the_reference():
    """MAX_SDF_DEPTH levels compile into the distance kernel and into the path tracer's."""
    from renderer.camera import CameraFrame
    from renderer.renderer import Renderer

    objects = (deepest_chain(schema.MAX_SDF_DEPTH),)
    assert max(_depth(o) for o in objects) == schema.MAX_SDF_DEPTH
    geometry = make_geometry(*objects)
    p = np.random.default_rng(6).uniform(-0.5, 2.0, (5000, 3)).astype(np.float32).astype(np.float64)
    assert_matches(geometry, objects, p, tol=4 * TOL)
    scene = make_scene(*objects)
    renderer = Renderer(scene, (8, 8))
    renderer.render(CameraFrame.from_spec(scene.camera), 1, "mis", seed=1)
    assert np.isfinite(renderer.image()).all()


def _depth(n) -> int:
    return 1 + max((_depth(c) for c in n.children), default=0)
