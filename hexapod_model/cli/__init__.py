"""The ``hexapod`` command line.

Every sub-command lives in a module of this package with ``register(subparsers)``; each
parses its arguments, calls the library, prints, and returns the exit code (see
:data:`hexapod_model.cli.main.EXIT_CODES`). ``main(argv)`` is testable: it returns the code.
"""

from .main import main

__all__ = ["main"]
