"""Figures and reports drawn from result objects (no computation here)."""
