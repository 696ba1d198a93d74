"""What a model file that still loads can be warned about (one line naming the file)."""


class MeshWarning(UserWarning):
    """Something in a model file was repaired or skipped; the model still loads."""


class DegenerateTrianglesWarning(MeshWarning):
    """Zero-area triangles or triangles with a repeated vertex were removed."""
