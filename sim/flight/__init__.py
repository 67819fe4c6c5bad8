"""Flying a trimmed JSBSim aircraft: the simulation loop and flights with disturbances."""
