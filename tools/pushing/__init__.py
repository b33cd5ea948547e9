"""Quasi-static push mechanics of a round object under a tool (docs/design.md section 10)."""
