"""The test hands of the camera evaluation: off-grid model hands and the mesh hand."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from .._checks import check_integer, check_number
from ..errors import InvalidInputError
from ..estimate import SelectionOptions, select_shape, shape_ratios
from ..models import GRID_LEVELS, HandMeasurements, HandShape, model_measurements
from ._options import _NORMALIZE, EvalOptions
from ._stats import _num, ratio_distance

__all__ = ["random_hand_shapes"]

#: The largest `margin` of :func:`random_hand_shapes`, in grid steps (the bound of
#: ``EvalOptions.ratio_margin``): 4 steps beyond the outer levels keep every ratio within
#: what :class:`HandShape` accepts.
_MAX_MARGIN = 4.0

#: Draws of one ratio before :func:`random_hand_shapes` gives up landing off the grid levels
#: (over a range of at least 0.1, rounded to 4 decimals, a draw lands on a level about once in
#: 300 draws, so this is never reached by chance).
_MAX_REDRAWS = 100


def random_hand_shapes(n: int, *, seed: int = 0, margin: float = 0.5) -> list[HandShape]:
    """`n` hand shapes with uniform random ratios over the grid's range plus `margin` steps.

    Parameters
    ----------
    n : int
    seed : int, keyword-only
    margin : float, keyword-only
        Grid steps beyond the outer levels (module docstring).

    Returns
    -------
    list of HandShape
        Ratios rounded to 4 decimals, never exactly on a grid level.

    Raises
    ------
    InvalidInputError
        `n` or `seed` not an integer >= 0, or `margin` not a finite number in
        [0, 4] (as ``EvalOptions.ratio_margin``: below 0 the draw range shrinks to
        nothing and no draw is off the levels; beyond 4, ratios may leave the
        range :class:`HandShape` accepts).
    """
    n = check_integer(n, "n", minimum=0)
    seed = check_integer(seed, "seed", minimum=0)
    margin = check_number(margin, "margin", minimum=0.0, maximum=_MAX_MARGIN)
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0x4A11D]))
    out = []
    for _ in range(n):
        ratios = {}
        for name, (lo, mid, hi) in GRID_LEVELS.items():
            ratios[name] = _draw_off_levels(rng, (lo, mid, hi), margin, name)
        out.append(HandShape(**ratios))
    return out


def _draw_off_levels(rng: np.random.Generator, levels: tuple[float, float, float], margin: float,
                     name: str) -> float:
    """A ratio drawn uniformly over the levels' range plus `margin` steps, rounded to 4
    decimals and not on a level; redrawn a bounded number of times."""
    lo, mid, hi = levels
    a, b = lo - margin * (mid - lo), hi + margin * (hi - mid)
    for _ in range(_MAX_REDRAWS):  # rounding may land on a level: draw again
        v = round(float(rng.uniform(a, b)), 4)
        if v not in levels:
            return v
    raise InvalidInputError(f"random_hand_shapes: no {name} ratio off the grid levels {levels} "
                            f"in {_MAX_REDRAWS} draws over [{a:g}, {b:g}] (margin={margin!r})")


def _pose_seed(seed: int, hand: int, set_index: int) -> int:
    ss = np.random.SeedSequence([seed, hand, set_index, 0x9053])
    return int(ss.generate_state(1)[0] % (2**31 - 1)) + 1  # never the databases' seed 0


@dataclass
class _TestHand:
    """One test hand: how to render it and which databases it is looked up in."""

    index: int
    kind: str
    ratios: HandShape | None  # true ratios (model hands); None when unknown
    measurements: HandMeasurements | None
    databases: dict = field(default_factory=dict)  # condition -> grid HandShape
    selection: dict = field(default_factory=dict)  # normalize -> continuous ratios
    note: str = ""

    def distance(self, condition: str) -> float:
        if condition == "own_shape":
            return 0.0  # its frames are rendered from the database's own grid shape
        if self.ratios is None:
            return float("nan")
        return ratio_distance(self.ratios, self.databases[condition])

    def model_ratios(self) -> HandShape:
        """The true ratios of a model hand: the shape it is rendered with."""
        # _plan_hands gives every model hand its ratios; only a mesh hand's may be unknown
        assert self.kind == "model" and self.ratios is not None
        return self.ratios

    def as_dict(self) -> dict:
        return {
            "index": self.index,
            "kind": self.kind,
            "ratios": None if self.ratios is None else self.ratios.as_dict(),
            "selection_ratios": {k: {n: round(v, 5) for n, v in s.as_dict().items()}
                                 for k, s in self.selection.items()},
            "databases": {c: s.name for c, s in self.databases.items()},
            "ratio_distance": {c: _num(self.distance(c)) for c in self.databases},
            "note": self.note,
        }


def _mesh_renderer_factory():
    from ..testhands import MeshHandRenderer

    return MeshHandRenderer


def _mesh_measurements(renderer) -> HandMeasurements | None:
    m = getattr(renderer, "measurements", None)
    if callable(m):
        m = m()
    return m if isinstance(m, HandMeasurements) else None


def _plan_hands(options: EvalOptions, mesh_measurements: HandMeasurements | None) -> list[_TestHand]:
    standard = HandShape()
    hands = []
    shapes: Sequence[HandShape] = ()  # the model hands' true ratios
    if options.hand == "model":
        shapes = (options.hand_shapes if options.hand_shapes is not None else
                  random_hand_shapes(options.n_hands, seed=options.seed,
                                     margin=options.ratio_margin))
    for i in range(options.n_hands):
        if options.hand == "model":
            hand = _TestHand(i, "model", shapes[i], model_measurements(shapes[i]))
        else:
            hand = _TestHand(i, "mesh", None, mesh_measurements)
            if mesh_measurements is not None:
                # true ratios unknown: the formulas' ratios of its millimetres stand in
                try:
                    hand.ratios = shape_ratios(mesh_measurements, model_measurements(standard),
                                               normalize="none")
                    hand.note = ("ratios measured on the mesh by formulas (1)-(4) without "
                                 "normalisation (its true ratios are unknown)")
                except InvalidInputError as exc:
                    hand.note = f"mesh ratios unusable for the ratio distance: {exc}"
        for cond in options.conditions:
            if cond == "standard":
                hand.databases[cond] = standard
                continue
            if cond == "personal":
                hand.databases[cond] = _personal_shape(hand, options)
                continue
            if cond == "calibrated":
                continue  # chosen from the hand's open-hand frame in evaluate()
            norm = _NORMALIZE.get(cond, "palm_width")
            if hand.measurements is None:
                hand.databases[cond] = standard
                hand.note = "no measurements from the test hand: selected = standard database"
                continue
            sel = select_shape(hand.measurements, options=SelectionOptions(normalize=norm))
            hand.selection[norm] = sel.ratios
            hand.databases[cond] = sel.shape
        hands.append(hand)
    return hands


def _personal_shape(hand: _TestHand, options: EvalOptions) -> HandShape:
    """The shape of the hand's personal database: measured on a photo (model hands)."""
    from ..measure import measure_photo, render_measurement_photo

    if hand.kind == "mesh":
        if hand.ratios is None:
            hand.note = "no measurements from the test hand: personal = standard database"
            return HandShape()
        return HandShape.from_name(hand.ratios.name)
    # a model hand is planned with its true ratios and their measurements
    assert hand.measurements is not None
    rng = np.random.default_rng([options.seed, hand.index, 0x50484F54])
    scale = options.photo_mm_per_px
    photo = render_measurement_photo(hand.model_ratios(), mm_per_px=scale, side=options.side,
                                     roll_deg=float(rng.uniform(-180.0, 180.0)))
    try:
        shape = measure_photo(photo.image, mm_per_px=scale).shape
    except InvalidInputError as exc:
        grid = select_shape(hand.measurements, options=SelectionOptions(normalize="none")).shape
        hand.note = f"photo not measurable ({exc}): personal = {grid.name}"
        return grid
    hand.selection["photo"] = shape
    return HandShape.from_name(shape.name)
