"""Contact faces derived from a tool's outline (docs/design.md section 12)."""
