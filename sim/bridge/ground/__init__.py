"""The bridge's ground side: recording a stream and converting a tlog into a FlightRecord
with its time base, gaps and clock alignment (``flightid.sim.bridge``). Nothing here
imports the air side."""
