"""One module per ``symloc`` sub-command; each defines ``register(subparsers)``."""
