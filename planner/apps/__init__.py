"""Applications: the command line, the paper's run, batch runs, figures, and the scripted operator that
records demonstrations on the simulator."""
