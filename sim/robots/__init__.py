"""Shipped robot profiles (YAML)."""
