"""The ranked choice of a tool for a task (``tooltransfer choose``, :func:`tooltransfer.choose_tool`).

Every candidate tool plans the task (:mod:`.candidates` turns library names and tool files into one
task each; :mod:`.run` plans them in parallel, :mod:`.schedule` runs the pools and the deadline of
the candidates still planning once a plan has passed every execution); each solved plan is executed
on the simulated platform open and closed loop and closed loop on a mismatched plant
(:mod:`.executions`); the candidates are ranked by what the executions achieved, then by the plans'
margins and duration (:mod:`.ranking`).
"""
