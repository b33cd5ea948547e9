"""Figures (matplotlib, Agg backend): one module per kind of figure; each function takes an output path."""
