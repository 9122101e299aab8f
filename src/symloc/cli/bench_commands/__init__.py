"""Sub-commands of ``symloc bench``: one module each, discovered (see :func:`register`)."""
