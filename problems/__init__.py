"""Task specifications, their schema, and the project's named task files."""
