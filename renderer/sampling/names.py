"""The samplers a scene file or the command line may name, in one place: the scene schema lists
them without importing Taichi, and `sampler.make_sampler` builds them."""
SAMPLERS = ("independent", "sobol")
