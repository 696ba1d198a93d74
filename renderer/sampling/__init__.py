"""Random numbers and warps from the unit square to directions and points."""
