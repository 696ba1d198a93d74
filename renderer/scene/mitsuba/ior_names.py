"""The named indices of refraction a Mitsuba 3 scene may give as `int_ior` / `ext_ior` strings.

The values are the physical constants Mitsuba's own table lists (at visible wavelengths, about
589 nm), from the standard references for each substance.
"""
IOR_NAMES = {
    "vacuum": 1.0,
    "helium": 1.00004,
    "hydrogen": 1.00013,
    "air": 1.00028,
    "carbon dioxide": 1.00045,
    "water": 1.3330,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.470,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.5750,
    "diamond": 2.419,
}
