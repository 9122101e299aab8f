"""Experiments: one module per table or figure; each defines ``register(subparsers)``.

Every experiment takes ``--seed``, prints its seed and configuration first, and can write its
results as JSON (``--json PATH``) and a PNG figure.
"""
