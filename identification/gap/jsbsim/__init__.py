"""The diagnosis carried back to the JSBSim aircraft: the corrected aircraft written
(``write``), the model's even terms a symmetric airframe cannot have (``symmetry``), the
named effect refined with the aircraft itself (``refine``), and both aircraft flown again
window by window (``refly``).
"""
