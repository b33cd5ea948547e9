"""Quasi-static push mechanics of a round object under a tool (DESIGN section 10)."""
