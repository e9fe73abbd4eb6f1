"""Compatibility aliases of the paper's benchmark tasks."""
