"""Executing a plan: the plant protocol, open-loop simulation, the closed loop, export to the robot's formats."""
