"""`bench bvh` with the wide traversals and the packet leaves among its knobs: the wide4 / stack
and packet / scalar figures it reports are the ratios of its own measurements, and the default's
shadow rays agree with the binary tree's."""
import pytest

from renderer.bench import bvh_measure
from tests.bench.test_bench_bvh import TINY, tiny_config


def test_wide_traversal_is_measured_against_the_binary_one():
    packets = bvh_measure.PACKETS
    default = bvh_measure.DEFAULT[1]  # the Renderer's traversal (8-wide, packet leaves)
    traversals = ("stack", bvh_measure.WIDE, "stack" + packets, bvh_measure.WIDE + packets, default)
    config = tiny_config(strategies=("sah",), traversals=traversals)
    res = bvh_measure.measure_mesh(TINY.name, TINY.load(), config, None, None, log=lambda *a: None)
    configs = {c["traversal"]: c for c in res["configs"]}
    assert set(configs) == set(traversals)
    (row,) = res["wide_vs_binary"]
    assert (row["strategy"], row["triangle_test"]) == ("sah", "watertight")
    for kind in ("coherent", "incoherent"):
        wide, binary = configs[bvh_measure.WIDE][kind], configs["stack"][kind]
        assert row[kind]["speedup"] == pytest.approx(wide["mrays_per_s"] / binary["mrays_per_s"])
        assert row[kind]["wide_nodes_per_ray"] == wide["nodes_per_ray"]
        # a wide node stands for up to three binary ones; the same rays hit
        assert wide["nodes_per_ray"] < binary["nodes_per_ray"]
        assert wide["hit_fraction"] == binary["hit_fraction"]
    build = res["builds"][0]
    assert build["wide_device_bytes"]["bvh"] < build["device_bytes"]["bvh"]
    # shadow rays on the Renderer's configuration and on the binary tree, the same answers
    shadow = res["shadow"]
    assert shadow["config"] == bvh_measure.config_name(*bvh_measure.DEFAULT)
    assert shadow["other"]["config"] == "sah/stack+packets/watertight"
    assert shadow["other"]["occluded_mrays_per_s"] > 0 and shadow["other"]["agreement"] == 1.0
    # packet / scalar leaves per traversal: the ratio of the two rows, the same hits; the packet
    # configurations run on the tree the Renderer builds for packet leaves (larger leaves)
    rows = {r["traversal"]: r for r in res["packets_vs_scalar"]}
    assert set(rows) == {"stack", bvh_measure.WIDE}
    assert build["packet_tree"]["max_leaf_size"] == bvh_measure.PACKET_LEAF > bvh_measure.DEFAULT_LEAF
    assert build["packet_tree"]["leaves"] < build["leaves"]
    for base, r in rows.items():
        for kind in ("coherent", "incoherent"):
            packed, scalar = configs[base + packets][kind], configs[base][kind]
            assert r[kind]["speedup"] == pytest.approx(packed["mrays_per_s"] / scalar["mrays_per_s"])
            assert packed["hit_fraction"] == scalar["hit_fraction"]
    assert build["wide_packets_device_bytes"]["per_triangle"] <= bvh_measure.BYTES_PER_TRIANGLE_TARGET
