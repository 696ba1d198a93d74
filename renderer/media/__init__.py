"""Participating media: phase functions, homogeneous and grid media, as Taichi funcs with numpy
references. Library pieces for the integrators; nothing here calls ti.init.

phase        Henyey-Greenstein phase function: evaluation and exact inverse-CDF sampling
homogeneous  transmittance, free-flight distance sampling with spectral MIS over the RGB
             channels (pbrt-v3's HomogeneousMedium::Sample), and the exponential-fog blend
grid         media on 3D grids: trilinear / nearest lookups, free flights by delta (spectral)
             tracking and transmittance by ratio tracking
table        a scene's media and fog as device data
grid_table   a scene's grid media as device data (their records, grids and voxels)
"""
