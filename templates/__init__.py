"""jinja2 templates of the generated C (package data, see codegen/resources.py)."""
