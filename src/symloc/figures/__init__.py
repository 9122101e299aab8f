"""Figures (matplotlib). The only package that imports matplotlib."""
