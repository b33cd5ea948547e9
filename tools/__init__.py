"""Tool and object geometry, the Phantom Omni arm, and the simulated platform."""
