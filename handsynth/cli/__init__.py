"""The ``handsynth`` command line: it parses arguments and calls the library."""

from ._main import main

__all__ = ["main"]
