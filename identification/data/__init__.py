"""Data preparation before identification: windows, coefficients, unit checks, time bases, input
denoising, multistep inputs, data reduction.
"""
