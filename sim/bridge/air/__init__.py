"""The bridge's air side: serving a flight over a link, the recorder's stream schedule, the
signing of controls, and the onboard logs (DataFlash, ULog) of a flight
(``flightid.sim.bridge``)."""
