"""Ship the default ensemble's perceptrons with handsynth (maintainers' tool).

Reads (or learns, 18-28 min each on two cores, plus 18-20 min for each
16,000-hand learning set to render) every perceptron member of
:data:`handsynth.estimate.LEARNED_ENSEMBLE`, for the default and the
relaxed-rest learning set (:func:`handsynth.estimate.shipped_perceptrons`),
from ``--cache`` with the shipped files ignored, then copies them into
``handsynth/estimate/shipped/`` with the fingerprints of their learning sets
and a new ``manifest.json``
(:mod:`handsynth.estimate._shipped`).  Run it when the ensemble's perceptrons,
their options or their learning sets change, or when
``tests/estimate/test_shipped.py`` says a fingerprint no longer matches.

    python scripts/ship_perceptrons.py --cache DIR
"""

from __future__ import annotations

import argparse
from pathlib import Path

from handsynth.estimate import learned_estimator, shipped_perceptrons
from handsynth.estimate._learned import learned_file_name
from handsynth.estimate._shipped import ship
from handsynth.render import CameraMount


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cache", required=True, type=Path,
                    help="folder of learnt estimators and learning sets (learnt there when missing)")
    args = ap.parse_args()
    mount = CameraMount.paper()
    sources = {}
    for opts, data in shipped_perceptrons():
        learned_estimator(args.cache, opts, data=data, mount=mount, shipped=False, progress=print)
        name = learned_file_name(opts, data, mount, "right")
        sources[name] = (args.cache / name, data)
    manifest = ship(sources, mount=mount)
    for name, entry in manifest["files"].items():
        print(f"shipped {name}: {entry['bytes']} bytes, fingerprint {entry['fingerprint']}")


if __name__ == "__main__":
    main()
