"""Matplotlib figures (headless, Agg), written atomically."""
