"""Spectra, colour and the paper's fit (being written)."""
Spectrum = spectrum = xyz = fit = Fit = None
