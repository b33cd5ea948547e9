"""What every part of the planner may use: the units of a plan's metrics, the command line's exit codes and
output check."""
