"""JSBSim aircraft definitions and their truth files; ``path()`` finds them."""
