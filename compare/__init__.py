"""Comparison layer and figures for the dem engine."""
