"""Figures of dem run directories and of the comparison (matplotlib)."""
