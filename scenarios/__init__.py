"""Input designs, flight cards, studies and the ``flightid`` command line."""
