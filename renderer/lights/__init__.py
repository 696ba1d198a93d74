"""Emitters: the environment (map, sky or constant) and, later, area lights and light selection."""
