"""The film: what is accumulated and stored per pixel.

accumulation.py       `Film` / `FilmState`: running means, Welford M2, counts, rejected samples
pixel_fields.py       how per-pixel fields are laid out in memory
pixel_slices.py       a sample per pixel split into interleaved slices (frame budgets, distribution)
band_table.py         the rows of a round cut into bands, on the device
adaptive.py           adaptive sampling: precise pixels stop taking samples
aovs.py               albedo and normal beside the colour, for the denoiser and the AOV views
crop_window.py        where a film lies on the camera's image (a crop window; plain Python)
"""
