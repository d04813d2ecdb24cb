"""The renderer (being written)."""
render = None
