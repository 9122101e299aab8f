"""The ``symloc`` command line: parses arguments, calls the library, prints, returns a code."""
