"""Environment maps (being written)."""
inspect = convert = read_spectral = upsample = None
