"""The named measured metals (renderer/materials/data/metals.csv, written by
scripts/make_metal_table.py) against numbers checked independently.

MITSUBA: what Mitsuba 3 (3.9.1, variant scalar_rgb) itself reports for its presets,
`mi.traverse(mi.load_dict({"type": "conductor", "material": name}))["eta.value"]` and
`["k.value"]`, printed as float32. The script reproduces Mitsuba's conversion, so the stored
values must equal these to float32 rounding (relative 1e-7). (All 71 presets were compared when
the table was made; the largest difference was 4e-9 relative: the nine digits the file keeps.)
"""
import numpy as np
import pytest

from renderer.materials.conductor_ior import conductor_ior_row, fresnel_average, fresnel_conductor_np
from renderer.materials.metals import metal_ior, metal_names, metal_source
from renderer.scene import schema
from renderer.scene.description import MaterialSpec

MITSUBA = {
    "Au": ((0.14303597807884216, 0.3753070831298828, 1.4420453310012817),
           (3.982996940612793, 2.38555645942688, 1.6033592224121094)),
    "Ag": ((0.15527619421482086, 0.11672795563936234, 0.13838763535022736),
           (4.828354358673096, 3.122222423553467, 2.1469011306762695)),
    "Al": ((1.6575008630752563, 0.8804047107696533, 0.521244466304779),
           (9.223811149597168, 6.26950216293335, 4.8370041847229)),
    "Cu": ((0.2010054737329483, 0.9237495064735413, 1.1022154092788696),
           (3.913262128829956, 2.453045129776001, 2.14208984375)),
    "Cr": ((4.3696675300598145, 2.9165053367614746, 1.6549046039581299),
           (5.206546783447266, 4.231306076049805, 3.7546987533569336)),
    "W": ((4.370816707611084, 3.300246477127075, 2.9984073638916016),
          (3.500640630722046, 2.6048738956451416, 2.27323317527771)),
    "Ni_palik": ((2.367304563522339, 1.6633731126785278, 1.4670780897140503),
                 (4.498811721801758, 3.0501530170440674, 2.3454391956329346)),
}
# Mitsuba 3's conductor presets (its conductor plugin's documentation lists them), and the four
# metals added from refractiveindex.info.
MITSUBA_PRESETS = (
    "a-C", "Ag", "Al", "AlAs", "AlAs_palik", "AlSb", "AlSb_palik", "Au", "Be", "Be_palik", "Cr", "CsI", "CsI_palik",
    "Cu", "Cu_palik", "Cu2O", "Cu2O_palik", "CuO", "CuO_palik", "d-C", "d-C_palik", "Hg", "Hg_palik", "HgTe",
    "HgTe_palik", "Ir", "Ir_palik", "K", "K_palik", "Li", "Li_palik", "MgO", "MgO_palik", "Mo", "Mo_palik",
    "Na_palik", "Nb", "Nb_palik", "Ni_palik", "Rh", "Rh_palik", "Se", "Se_palik", "SiC", "SiC_palik", "SnTe",
    "SnTe_palik", "Ta", "Ta_palik", "Te", "Te_palik", "ThF4", "ThF4_palik", "TiC", "TiC_palik", "TiN", "TiN_palik",
    "TiO2", "TiO2_palik", "VC", "VC_palik", "V_palik", "VN", "VN_palik", "W")
ADDED = ("Fe", "Ni", "Pt", "Ti")


@pytest.mark.parametrize("name", sorted(MITSUBA))
def test_values_equal_what_mitsuba_reports(name):
    eta, k = metal_ior(name)
    np.testing.assert_allclose(eta, MITSUBA[name][0], rtol=1e-7)
    np.testing.assert_allclose(k, MITSUBA[name][1], rtol=1e-7)


def test_every_mitsuba_preset_and_the_added_metals_are_there():
    names = set(metal_names())
    assert set(MITSUBA_PRESETS) <= names and set(ADDED) <= names
    for name in ADDED:
        assert metal_source(name).startswith("refractiveindex.info")
    assert schema.MATERIAL.field("metal").choices == metal_names()


def test_normal_incidence_colours_are_those_of_the_metals():
    """F0 from the table (the closed form ((n-1)^2 + k^2) / ((n+1)^2 + k^2)): silver and aluminium
    nearly white and bright, gold and copper red > green > blue, every metal between 0 and 1."""
    def f0(name):
        eta, k = map(np.asarray, metal_ior(name))
        return ((eta - 1) ** 2 + k ** 2) / ((eta + 1) ** 2 + k ** 2)

    assert (f0("Ag") > 0.9).all() and (f0("Al") > 0.85).all()
    for name in ("Au", "Cu"):
        r, g, b = f0(name)
        assert r > g > b
    for name in metal_names():
        assert ((f0(name) >= 0.0) & (f0(name) <= 1.0)).all()
        np.testing.assert_allclose(fresnel_conductor_np([1.0], *metal_ior(name))[0], f0(name), rtol=1e-12)


def test_table_row_of_a_named_metal():
    gold = MaterialSpec(name="gold", kind="conductor", metal="Au", roughness=0.3)
    row = conductor_ior_row(gold)
    assert row["complex_ior"] == 1
    np.testing.assert_allclose(row["fresnel_avg"], fresnel_average(row["eta"], row["k"]))
    written = conductor_ior_row(MaterialSpec(name="g", kind="conductor", eta=row["eta"], k=row["k"]))
    assert written == row
    for plain in (MaterialSpec(name="c", kind="conductor"), MaterialSpec(name="d", kind="diffuse"), None):
        assert conductor_ior_row(plain)["complex_ior"] == 0
