"""The shipped tool files (one YAML per tool); read them with :func:`tools.load_tool`."""
