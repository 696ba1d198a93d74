"""Participating media: phase functions and homogeneous media, as Taichi funcs with numpy
references. Library pieces for the integrators; nothing here calls ti.init.

phase        Henyey-Greenstein phase function: evaluation and exact inverse-CDF sampling
homogeneous  transmittance, free-flight distance sampling with spectral MIS over the RGB
             channels (pbrt-v3's HomogeneousMedium::Sample), and the exponential-fog blend
table        a scene's media and fog as device data (the one module here that owns fields)
"""
