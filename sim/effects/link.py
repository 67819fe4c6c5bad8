"""Link faults (catalogue ``link``): what a real telemetry link does to the bridge's packets.

``corrupt`` (probability per byte), ``drop`` (probability per packet), ``latency`` (s) and
``jitter`` (s, standard deviation) are declared in the catalogue and injected by the
bridge's own ``LinkFaults`` and ``Transmitter`` (``flightid.sim.bridge.link``): the
catalogue names that class and maps each entry's parameter to its field, e.g.
``drop.probability`` -> ``LinkFaults.drop``. On the command line they are the bridge's
``--faults drop=0.01,latency=0.05`` (entry name = value of its parameter).
"""

from __future__ import annotations

from flightid.sim.effects.base import ExternalImplementation

LINK_FAULTS = "flightid.sim.bridge.link:LinkFaults"
HOW = "BridgeConfig(faults=LinkFaults(...)); command line: flightid bridge serve --faults"


def link_fault(field: str, parameter: str) -> ExternalImplementation:
    """The bridge's ``LinkFaults.<field>`` as the implementation of one catalogue parameter.

    Parameters
    ----------
    field : str
        The ``LinkFaults`` field.
    parameter : str
        The catalogue parameter it implements.

    Returns
    -------
    ExternalImplementation
        The mapping of ``parameter`` onto ``field``.
    """
    return ExternalImplementation(LINK_FAULTS, ((parameter, field),), HOW)
