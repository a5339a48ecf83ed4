"""Simulation mode: the lock-step loop that advances the world, the bus and the agents,
as fast as the CPU allows."""
