"""Verdicts a task can defend: ``solved``, ``infeasible`` with a certificate, or ``unknown``.

The rules a plan must follow (:class:`~tooltransfer.planner.planning.verdicts.rules.PushRules`), the regions
and directions they allow, over-approximated (:mod:`~tooltransfer.planner.planning.verdicts.bounds`), the
backward-reachable set of the target under them (:mod:`~tooltransfer.planner.planning.verdicts.backward`), and
the certificates built on it and checked again independently
(:mod:`~tooltransfer.planner.planning.verdicts.certificate`).
"""
