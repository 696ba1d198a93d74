"""The coated kind's bases (renderer/materials/coated.py): the scene file's names and the device ids."""
COAT_BASES = {"diffuse": 0, "conductor": 1}
