"""Shipped world files (YAML) and their converter, build_worlds.py."""
