"""Would a second calibration frame in a hook pose tell the per-digit estimator the index PIP?

The per-digit estimator reads a flexed index PIP poorly on paper frames
(docs/camera_estimator.md, "Where it fails"): the index cells say "flexed" but not how much,
because how far the silhouette shortens depends on the hand's own phalanx
lengths.  A frame of the hand in a hook pose (knuckles straight, fingers
bent at the middle joints) shows where the proximal phalanx ends, so a user
could give it after the rest frame.  This study asks whether it helps,
before any of it enters the library.

A learning set of ``--hands`` random model hands (as
:func:`handsynth.db.render_learning_set` makes them, 100 frames each) also
renders each hand in a hook pose (MCP -5 to 15 deg, PIP 65 to 105, DIP 0.3
to 0.9 of the PIP, from its rest).  Test hands: four held-out model hands
(seed 11, 1.5 times the learning spread: the choice) and the two glTF hands
(printed, never used to choose), each with its relaxed rest posture and a
hook drawn by another generator (PIP about 85 +- 8 deg shared by the
fingers plus 6 deg each, MCP about 4 deg plus a third of the rest, DIP about
40 deg), 300 paper-protocol and 300 natural frames (poses seed 0).  The
index digit (MCP, abduction, PIP, DIP) is read as the library's per-digit
estimator does (the digit's cells, 64 principal components, 128 nearest
neighbours, the local linear fit with ridge 3; exact search), with the
inputs

- ``rest``: the frame and its difference from the rest frame (the library's);
- ``hook_grid``: also the hook frame's difference from the rest frame;
- ``hook_codes``: ``rest`` plus the first 4 principal components of the
  hook frame's difference from the rest frame over the digit's cells,
  scaled to the first component's spread.

Per hand and pose set: the index flexion MAE (MCP, PIP, DIP), the constant
open hand's, and the index PIP MAE on frames where it moves more than 20 deg
from rest (number of frames).  Last line: ``<variant>_paper_pip=<mean over
the model hands> ...``.

Usage::

    python scripts/study_camera_hook.py [--hands 1000]
"""

from __future__ import annotations

import argparse

import faiss
import numpy as np

from handsynth.db import LearningSetOptions
from handsynth.db._learning import _edge, _random_shape, learning_poses, random_rest_posture
from handsynth.estimate import local_linear
from handsynth.eval._protocol import _seed, mesh_test_hands, model_test_hands
from handsynth.eval._testposes import natural_test_poses, paper_protocol_poses, relaxed_rest_posture
from handsynth.models import JOINT_LIMITS_DEG, HandShape
from handsynth.render import CameraMount, HandVariation, VariedRasterizer, coverage

_DIGIT = [4, 5, 6, 7]          # index MCP flexion, abduction, PIP, DIP
_FLEX = [0, 2, 3]              # of those, the flexions
_LO, _HI = JOINT_LIMITS_DEG[:, 0], JOINT_LIMITS_DEG[:, 1]
VARIANTS = ("rest", "hook_grid", "hook_codes")


def learning_hook(rest: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    a = rest.copy()
    for k in range(4):
        j = 4 + 4 * k
        a[j] = rng.uniform(-5, 15)
        a[j + 2] = rng.uniform(65, 105)
        a[j + 3] = a[j + 2] * rng.uniform(0.3, 0.9)
    return np.clip(a, _LO, _HI)


def test_hook(rest: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    a = rest.copy()
    pip = rng.normal(85, 8)
    for k in range(4):
        j = 4 + 4 * k
        a[j] = rest[j] * 0.3 + rng.normal(4, 4)
        a[j + 2] = pip + rng.normal(0, 6)
        a[j + 3] = rng.normal(40, 12)
    return np.clip(a, _LO, _HI)


def _grid(mask: np.ndarray, mount: CameraMount, cells) -> np.ndarray:
    return np.rint(coverage(mask, mount, cells=cells) * 255).astype(np.uint8).ravel()


def learning_data(hands: int, *, per: int = 100, seed: int = 123) -> dict:
    opts = LearningSetOptions()
    mount = CameraMount.paper()
    rng = np.random.default_rng(seed)
    built: dict = {}
    grids, rests, hooks, angles = [], [], [], []
    for _ in range(hands):
        shape = _random_shape(rng)
        key = round(shape.length, 1), round(shape.width, 1)
        if key not in built:
            built[key] = VariedRasterizer(HandShape(length=key[0], width=key[1]), mount)
        r = built[key]
        r.vary(HandVariation.random(rng, spread=opts.hand_spread))
        r.set_mount(opts.mount_variation.sample(mount, rng))
        edge = int(rng.integers(-opts.edge_px, opts.edge_px + 1))
        rest = random_rest_posture(rng)
        poses = learning_poses(rest, per, rng, mix=opts.mix)
        hook = learning_hook(rest, rng)
        rests.append(_grid(_edge(r.mask(rest), edge), mount, opts.cells))
        hooks.append(_grid(_edge(r.mask(hook), edge), mount, opts.cells))
        grids.append(np.stack([_grid(_edge(r.mask(p), edge), mount, opts.cells) for p in poses]))
        angles.append(poses)
    return {"grids": np.concatenate(grids), "rest": np.stack(rests), "hook": np.stack(hooks),
            "angles": np.concatenate(angles).astype(np.float32),
            "hand": np.repeat(np.arange(hands), per)}


def test_data(hands, *, frames: int = 300, seed: int = 0) -> list[dict]:
    mount = CameraMount.paper()
    cells = LearningSetOptions().cells
    out = []
    for hand in hands:
        rest = relaxed_rest_posture(np.random.default_rng(_seed(seed, hand.name, "rest")))
        hook = test_hook(rest, np.random.default_rng(_seed(seed, hand.name, "hook")))
        maker = hand.make()
        try:
            rec = {"name": hand.name, "kind": hand.kind, "rest": rest,
                   "rest_grid": _grid(maker.mask(rest), mount, cells),
                   "hook_grid": _grid(maker.mask(hook), mount, cells)}
            for ps, gen in (("paper", paper_protocol_poses), ("natural", natural_test_poses)):
                poses, _ = gen(rest, frames, np.random.default_rng(_seed(seed, hand.name, ps)))
                rec[ps] = (np.stack([_grid(m, mount, cells) for m in maker.masks(poses)]), poses)
        finally:
            if hasattr(maker, "close"):
                maker.close()
        out.append(rec)
    return out


def _inputs(grids, rest, hook=None) -> np.ndarray:
    f = grids.astype(np.float32) / 255
    r = rest.astype(np.float32) / 255
    blocks = [f, f - r]
    if hook is not None:
        blocks.append(np.broadcast_to(hook.astype(np.float32) / 255 - r, f.shape))
    return np.hstack(blocks)


class DigitReader:
    """The index digit read as the library's per-digit estimator reads it (module docstring)."""

    def __init__(self, data: dict, variant: str, *, components: int = 64, hook_components: int = 4):
        self.variant = variant
        n_cells = data["grids"].shape[1]
        x = data["grids"].astype(np.float32) / 255
        y = data["angles"][:, _DIGIT]
        xc, yc = x - x.mean(axis=0), y - y.mean(axis=0)
        corr = np.abs(xc.T @ yc / len(y)) / (np.outer(xc.std(axis=0), yc.std(axis=0)) + 1e-6)
        w = corr.max(axis=1)
        cells = np.nonzero(w > 0.1)[0]
        blocks = 3 if variant == "hook_grid" else 2
        self.cols = np.concatenate([cells + b * n_cells for b in range(blocks)])
        self.weight = np.tile(w[cells], blocks).astype(np.float32)
        hook = data["hook"][data["hand"]] if variant == "hook_grid" else None
        z = _inputs(data["grids"], data["rest"][data["hand"]], hook)[:, self.cols] * self.weight
        self.mean = z.mean(axis=0)
        sample = np.random.default_rng(0).choice(len(z), min(20000, len(z)), replace=False)
        _, _, vt = np.linalg.svd(z[sample] - self.mean, full_matrices=False)
        self.components = vt[:components].T.astype(np.float32)
        codes = (z - self.mean) @ self.components
        if variant == "hook_codes":
            self.cells, self.cell_w = cells, w[cells].astype(np.float32)
            h = self._hook_diff(data["hook"], data["rest"])
            self.h_mean = h.mean(axis=0)
            _, _, hvt = np.linalg.svd(h - self.h_mean, full_matrices=False)
            self.h_components = hvt[:hook_components].T
            hc = (h - self.h_mean) @ self.h_components
            self.h_scale = codes[:, 0].std() / hc[:, 0].std()
            codes = np.hstack([codes, hc[data["hand"]] * self.h_scale])
        self.codes = np.ascontiguousarray(codes, np.float32)
        self.angles = y
        self.index = faiss.IndexFlatL2(self.codes.shape[1])
        self.index.add(self.codes)

    def _hook_diff(self, hook, rest) -> np.ndarray:
        d = (np.atleast_2d(hook).astype(np.float32) - np.atleast_2d(rest).astype(np.float32))
        return d[:, self.cells] / 255 * self.cell_w

    def read(self, grids, rest_grid, hook_grid, *, k: int = 128, ridge: float = 3.0) -> np.ndarray:
        hook = hook_grid[None] if self.variant == "hook_grid" else None
        z = _inputs(grids, rest_grid[None], hook)[:, self.cols] * self.weight
        c = (z - self.mean) @ self.components
        if self.variant == "hook_codes":
            hc = (self._hook_diff(hook_grid, rest_grid) - self.h_mean) @ self.h_components
            c = np.hstack([c, np.tile(hc * self.h_scale, (len(c), 1))])
        c = np.ascontiguousarray(c, np.float32)
        dist, idx = self.index.search(c, k)
        out = np.empty((len(c), len(_DIGIT)))
        for i in range(len(c)):
            d = np.sqrt(np.maximum(dist[i], 0.0))
            out[i] = local_linear(self.codes[idx[i]] - c[i], self.angles[idx[i]],
                                  1.0 / (d + d[0] + 1e-6), ridge=ridge)
        return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hands", type=int, default=1000, help="learning hands")
    args = ap.parse_args()
    data = learning_data(args.hands)
    tests = (test_data(model_test_hands(4, seed=11, spread=1.5))
             + test_data(mesh_test_hands()))
    print("index flexion MAE (constant) / index PIP MAE where it moves > 20 deg (frames), deg")
    summary = {}
    for variant in VARIANTS:
        reader = DigitReader(data, variant)
        for ps in ("paper", "natural"):
            cells, model_pip = [], []
            for t in tests:
                grids, poses = t[ps]
                got = reader.read(grids, t["rest_grid"], t["hook_grid"])
                truth = poses[:, _DIGIT]
                flex = np.abs(got[:, _FLEX] - truth[:, _FLEX]).mean()
                const = np.abs(truth[:, _FLEX]).mean()
                moving = np.abs(poses[:, 6] - t["rest"][6]) > 20
                pip = np.abs(got[moving, 2] - truth[moving, 2]).mean() if moving.any() else np.nan
                cells.append(f"{t['name']} {flex:.2f} ({const:.2f}) / {pip:.1f} ({moving.sum()})")
                if t["kind"] == "model":
                    model_pip.append(pip)
            summary[f"{variant}_{ps}_pip"] = float(np.nanmean(model_pip))
            print(f"{variant:10s} {ps:7s} " + "; ".join(cells), flush=True)
    print(" ".join(f"{k}={v:.2f}" for k, v in summary.items()))


if __name__ == "__main__":
    main()
