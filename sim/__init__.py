"""The simulator: JSBSim flight core, truth derivatives, sensors, disturbances, bridge."""
