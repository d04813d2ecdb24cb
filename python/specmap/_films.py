"""Thin films (being written)."""
thinfilm = None
