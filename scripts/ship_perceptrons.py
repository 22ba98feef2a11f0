"""Ship the default ensemble's perceptrons with handsynth (maintainers' tool).

Reads (or learns, 16-20 min each on two cores, plus 9 min for each
8,000-hand learning set to render) every perceptron member of
:data:`handsynth.estimate.LEARNED_ENSEMBLE` from ``--cache`` with the shipped
files ignored, then copies them into ``handsynth/estimate/shipped/`` with the
fingerprints of their learning sets and a new ``manifest.json``
(:mod:`handsynth.estimate._shipped`).  Run it when the ensemble's perceptrons,
their options or their learning sets change, or when
``tests/estimate/test_shipped.py`` says a fingerprint no longer matches.

    python scripts/ship_perceptrons.py --cache DIR
"""

from __future__ import annotations

import argparse
from pathlib import Path

from handsynth.db import LearningSetOptions
from handsynth.estimate import LEARNED_ENSEMBLE, learned_estimator, member_learning_set
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
    for opts, _weight, changes in LEARNED_ENSEMBLE:
        if opts.kind != "mlp":
            continue
        data = member_learning_set(LearningSetOptions(), changes)
        learned_estimator(args.cache, opts, data=data, mount=mount, shipped=False, progress=print)
        name = learned_file_name(opts, data, mount, "right")
        sources[name] = (args.cache / name, data)
    manifest = ship(sources, mount=mount)
    for name, entry in manifest["files"].items():
        print(f"shipped {name}: {entry['bytes']} bytes, fingerprint {entry['fingerprint']}")


if __name__ == "__main__":
    main()
