"""``python -m handsynth``: the ``handsynth`` command line."""

from handsynth.cli import main

if __name__ == "__main__":
    main()
