"""Spectral utilities for dispersion with hero-wavelength sampling (Wilkie et al. 2014).

wavelengths  sampling over [360, 830] nm: uniform, and the visible-importance density
             (Radziszewski et al. 2009, as in pbrt-v4) with its pdf; four hero wavelengths
cie          CIE 1931 colour matching functions (Wyman et al. 2013 fit), XYZ -> linear Rec.709,
             and the spectral -> RGB weights whose white is the constant spectrum 1
upsample     linear Rec.709 colour -> spectral value at a wavelength (white -> 1 exactly)
ior          Cauchy and Sellmeier index of refraction, presets for BK7, fused silica, SF11, water

Every module offers Taichi funcs (f32, bounded loops, no fields, valid on CPU, CUDA and Vulkan)
and float64 numpy references (`*_np`) for tests and scene preparation. Nothing here calls ti.init.

A spectral estimate of a pixel, with hero wavelengths:

    lams, pdfs = sample_hero_wavelengths(u)          # vec4, vec4
    for j: rgb += f(lams[j]) * spectral_rgb_weights(lams[j]) / (4 * pdfs[j])

where f is the path's spectral value (emitter spectrum times albedo spectra, each from
`rgb_to_spectrum`). With f = 1 the expectation is RGB (1, 1, 1) exactly.
"""
