"""Planning: QP and CasADi planning, push sequences, plans, the CLI and batch runs."""
