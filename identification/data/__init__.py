"""Data preparation before identification: the axes a record excites, windows,
coefficients, unit checks, time bases, input denoising, multistep inputs, data reduction.
"""
