"""Frequency-domain identification: frequency responses, transfer-function fits, state-space fits.
"""
