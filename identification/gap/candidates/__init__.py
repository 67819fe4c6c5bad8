"""The candidate effects of a gap diagnosis: entries of the effect catalogue expressed in
the linearised model.

``build`` (every candidate of a record, and pairs), the families ``sensor`` (sensor and
mounting), ``actuator`` and ``mass``; ``identifiable`` (the entries that are not
candidates, with the reason), ``ranges`` (the physical ranges) and ``classes`` (the
equivalence classes). The ``Candidate`` itself, and the edits of a linear model that the
families share, are in ``gap.model.edits``.
"""
