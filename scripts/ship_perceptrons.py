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
    python scripts/ship_perceptrons.py --add-limits [--hands 500]

``--add-limits`` learns nothing: it gives the shipped perceptrons, learnt
before perceptrons kept a novelty limit, the limit that learning them now
would keep (the 99th percentile of what their principal components leave out
of the learning frames' inputs; :mod:`handsynth.estimate._learned`), measured
on the first ``--hands`` hands of each one's learning set (a set's first hands
do not depend on how many it holds), and ships them again.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from handsynth.db import render_learning_set
from handsynth.estimate import LearnedEstimator, learned_estimator, shipped_perceptrons
from handsynth.estimate._learned import _NOVELTY_QUANTILE, _inputs, _left_out_norms, learned_file_name
from handsynth.estimate._shipped import ship, shipped_path
from handsynth.render import CameraMount


def _add_limits(hands: int, mount: CameraMount) -> None:
    from dataclasses import replace

    with tempfile.TemporaryDirectory() as tmp:
        sources, sets = {}, {}
        for opts, data in shipped_perceptrons():
            name = learned_file_name(opts, data, mount, "right")
            path = shipped_path(name)
            if path is None:
                raise SystemExit(f"{name} is not shipped intact; ship it with --cache first")
            est = LearnedEstimator.load(path, options=opts)
            if data not in sets:
                sets[data] = render_learning_set(replace(data, hands=hands), mount=mount,
                                                 side="right")
            ls = sets[data]
            z = _inputs(ls.grids, ls.rest_grids[ls.hand] if opts.use_rest else None)
            centred = z - est._a["mean"]
            norms = _left_out_norms(centred, centred @ est._a["components"])
            limit = np.array(np.quantile(norms, _NOVELTY_QUANTILE), np.float32)
            limit.setflags(write=False)
            est._a["novelty_limit"] = limit
            out = Path(tmp) / name
            est.save(out)
            sources[name] = (out, data)
            print(f"{name}: novelty limit {float(limit):.3f} from {len(norms)} frames of "
                  f"{hands} hands (median {np.median(norms):.3f}, largest {norms.max():.3f})")
        manifest = ship(sources, mount=mount)
    for name, entry in manifest["files"].items():
        print(f"shipped {name}: {entry['bytes']} bytes, fingerprint {entry['fingerprint']}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    what = ap.add_mutually_exclusive_group(required=True)
    what.add_argument("--cache", type=Path,
                      help="folder of learnt estimators and learning sets (learnt there when missing)")
    what.add_argument("--add-limits", action="store_true",
                      help="give the shipped perceptrons their novelty limits (learns nothing)")
    ap.add_argument("--hands", type=int, default=500,
                    help="--add-limits: learning-set hands the limits are measured on")
    args = ap.parse_args()
    mount = CameraMount.paper()
    if args.add_limits:
        _add_limits(args.hands, mount)
        return
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
