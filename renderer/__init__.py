"""Lantern's renderer: everything that computes an image. No GUI import anywhere below here."""
