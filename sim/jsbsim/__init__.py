"""The JSBSim aircraft: loading, flight condition, trim, truth derivatives, coefficients."""
