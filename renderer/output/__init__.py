"""What leaves the renderer: display values, image files, denoised images and checkpoints.

tonemap.py            exposure, tone mappers and the sRGB OETF (arrays and the viewer's canvas)
image_io.py           reading environment maps, writing PNG and EXR
denoise.py            Open Image Denoise on the film's colour and AOVs
render_outputs.py     what `render --denoise` and `--aovs` add to a render's files
checkpoint.py         a film's exact state and the render's identity, in one file
atomic_write.py       a file is either the old one or the complete new one, never torn
"""
