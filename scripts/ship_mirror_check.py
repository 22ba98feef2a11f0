"""Ship the mirror check with handsynth (maintainers' tool).

Learns :class:`handsynth.estimate.MirrorCheck` with its default options for the paper's
device (12,000 random model hands, about 40 s on one core) and writes it to
``handsynth/estimate/shipped/mirror_check.npz``, with the first hands of its learning set
as a fingerprint.  Run it when the check's options change, or when
``tests/estimate/test_rest_view.py`` says the fingerprint no longer matches (the hand
generator or the rasteriser changed).

    python scripts/ship_mirror_check.py
"""

from __future__ import annotations

import argparse
import time

from handsynth.estimate import MirrorCheck
from handsynth.estimate._rest_view import _SHIPPED


def main() -> None:
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_args()
    t0 = time.perf_counter()
    check = MirrorCheck.learn()
    check.save(_SHIPPED)
    print(f"learnt in {time.perf_counter() - t0:.0f} s; wrote {_SHIPPED} "
          f"({_SHIPPED.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    main()
