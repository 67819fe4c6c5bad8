"""The model under test: the aircraft linearised at a record's condition (``linearise``),
what the record's surface channels hold and the aircraft's own actuators on command
records (``surfaces``), and the edits of a linear model that the candidate effects make
(``edits``: the ``Candidate`` and its new parameters and states).
"""
