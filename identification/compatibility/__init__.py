"""Data compatibility: flight path reconstruction of sensor biases, scale factors and time shifts.
"""
