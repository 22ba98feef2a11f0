"""PoseLookup: the importable pose-lookup service (frame in, joint angles out).

One :class:`PoseLookup` holds one database in memory (read-only arrays,
loaded once) and may be shared by any number of threads: :meth:`estimate`
allocates its own scratch per call and the compiled search releases the
GIL.  Frames go through exactly the preprocessing the database was built
with (:func:`handsynth.render.preprocess` with the database's camera mount)
and the same features (:func:`handsynth.db.extract_features`).
"""

from __future__ import annotations

import copy
import inspect
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, runtime_checkable

import numpy as np

from .._checks import check_instance, check_options, check_path, check_side
from ..db import (
    BuildOptions,
    Database,
    build_databases,
    check_database_hand,
    check_rows,
    extract_features,
    find_database,
    open_database,
)
from ..errors import DatabaseError, InvalidInputError
from ..models import JOINT_NAMES, HandMeasurements, HandShape
from ..render import CameraMount, as_mount, check_frame, preprocess
from ._calibration import Calibration, reference_silhouette, select_shape_from_frame
from ._hand import MIN_HAND_COVERAGE, no_hand_error
from ._masked import masked_band_areas, masked_search
from ._search import SearchOptions, SearchTables, search
from ._selection import SelectionOptions, select_shape

__all__ = ["PoseEstimate", "PoseEstimator", "PoseLookup"]

#: Largest relative difference of a frame's width-to-height ratio from the device's
#: (:func:`check_frame_ratio`): a frame scaled to another size stays within it.
FRAME_RATIO_TOLERANCE = 0.01

#: Who needs the device's view, in :func:`check_frame_ratio`'s message for a lookup.
_LOOKUP_VIEW = "this lookup's database holds"


def check_frame_ratio(frame, mount: CameraMount, *, view: str) -> np.ndarray:
    """`frame`, refused unless it is an image of the device's width-to-height ratio.

    A frame of another ratio (a portrait frame, a 4:3 webcam for a 3:2
    device) is not the device's view: read as it, it would be stretched and
    matched wrong with no sign of it.  Frames of any size with the device's
    ratio (within :data:`FRAME_RATIO_TOLERANCE`) are the same view scaled.

    Parameters
    ----------
    frame : object
        What was given as a frame.
    mount : CameraMount
        The device; its ``width_px`` and ``height_px`` give the ratio.
    view : str
        Who needs the device's view, for the message (``"this estimator learnt"``).

    Returns
    -------
    ndarray
        `frame` itself.

    Raises
    ------
    InvalidInputError
        `frame` is not an image (:func:`~handsynth.render.check_frame`), or
        its width-to-height ratio is not the device's, naming its size.
    """
    frame = check_frame(frame)
    h, w = frame.shape[:2]
    want = mount.width_px / mount.height_px
    if abs(w / h - want) > FRAME_RATIO_TOLERANCE * want:
        raise InvalidInputError(
            f"frame is {w}x{h} pixels; {view} the device's {mount.width_px}x{mount.height_px} "
            "view: give frames of that width-to-height ratio (scaled, not cropped)")
    return frame


def _check_lookup_kwargs(kwargs: dict, where: str) -> None:
    """Refuse keyword arguments that :class:`PoseLookup` does not take, naming `where`."""
    # what PoseLookup takes besides its database: the keyword arguments its constructors pass on
    taken = [n for n, p in inspect.signature(PoseLookup).parameters.items()
             if p.kind is p.KEYWORD_ONLY]
    unknown = [k for k in kwargs if k not in taken]
    if unknown:
        raise InvalidInputError(
            f"{where}() got an unexpected keyword argument {unknown[0]!r} (it passes on to "
            f"PoseLookup only {', '.join(taken)})")


def _refuse_for_calibration(*, options, temporal, approximate) -> None:
    """Raise for a lookup option that a calibrated lookup cannot honour.

    Parameters
    ----------
    options : SearchOptions or None
        As given to :class:`PoseLookup` (``None``: not given).
    temporal : bool or None
        As given (``None``: not given; ``False`` is honoured trivially).
    approximate : object
        The approximate index or its request (``None`` or ``False``: none).

    Raises
    ------
    InvalidInputError
        Naming the option and the value received.
    """
    if approximate is not None and approximate is not False:
        got = repr(approximate) if isinstance(approximate, bool) else \
            f"<{type(approximate).__name__}>"
        raise InvalidInputError(
            f"a calibrated lookup needs the exact search, got approximate={got} (the "
            "approximate index); leave approximate unset")
    if options is not None:
        raise InvalidInputError(
            f"options={options!r} cannot be honoured by a calibrated lookup (its masked search "
            "has no E constants); leave options unset")
    if temporal:
        raise InvalidInputError(
            f"temporal={temporal!r} cannot be honoured by a calibrated lookup (its masked "
            "search takes no seed); pass temporal=False or leave temporal unset")


@dataclass(frozen=True, eq=False)
class PoseEstimate:
    """The pose found for one frame.

    Attributes
    ----------
    angles : ndarray of float64, shape (20,)
        Joint angles in degrees, canonical :data:`~handsynth.JOINT_NAMES`
        order; all NaN when `no_hand`.
    keypoints : ndarray of float32, shape (21, 3)
        Wrist, then base to tip per finger (thumb first), hand frame,
        metres; all NaN when `no_hand`.
    confidence : float
        In [0, 1]: ``exp(-E / (C3 * A_input))``, i.e. 1 for a perfect match
        and 1/e when the error equals every input ridge pixel lying outside
        the match; halved when the search had to fall back (no entry passed
        the pruning).  A calibrated lookup reports the IoU of input and match
        outside the ignore mask.  0 when `no_hand`.  A heuristic, not a
        probability.
    entry : int
        Index of the matched database entry, -1 when `no_hand`.
    error : float
        The search's ``E`` of that entry; for a calibrated lookup its pixel
        difference outside the ignore mask (inf when `no_hand`).
    low_confidence : bool
        No entry passed both pruning stages (SPEC.md section 1); for a
        :class:`~handsynth.estimate.LearnedEstimator`, the frame is more
        novel than 99 % of learning frames (its novelty limit: for the
        per-digit kind the distance to the nearest learning frame of another
        hand, for the perceptron what its principal components leave out of
        the frame); for an ensemble, any member's.
    no_hand : bool
        The frame shows no hand (empty silhouette after preprocessing, or a
        hand component covering less than
        :data:`~handsynth.estimate.MIN_HAND_COVERAGE` of the view).
    moved : bool
        For an estimator calibrated to a rest frame
        (:class:`~handsynth.estimate.LearnedEstimator`), the device seems to
        have moved on the wrist since that frame (:class:`~handsynth.estimate.MoveCheck`): take
        the rest frame again.  False otherwise.
    """

    angles: np.ndarray
    keypoints: np.ndarray
    confidence: float
    entry: int
    error: float
    low_confidence: bool
    no_hand: bool
    moved: bool = False

    def as_row(self) -> dict:
        """One flat row: ``entry, no_hand, confidence, low_confidence`` and the 20 angles."""
        row: dict[str, int | float | bool | None] = {
            "entry": self.entry, "no_hand": self.no_hand, "confidence": round(self.confidence, 6),
            "low_confidence": self.low_confidence}
        row.update({n: (None if np.isnan(v) else round(float(v), 4))
                    for n, v in zip(JOINT_NAMES, self.angles, strict=True)})
        return row


@runtime_checkable
class PoseEstimator(Protocol):
    """The interface every frame-based hand pose estimator of handsynth implements."""

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """Pose of the hand in one frame (BGR uint8 image or bool mask)."""
        ...



def _warn_rebuilt(summary) -> None:
    """Say which existing database a build replaced, and why (a database built with other
    options, e.g. ``build-db --default``'s 3,000 entries, is replaced by one of these)."""
    for reason in summary.rebuilt.values():
        warnings.warn(f"built again, replacing an existing file: {reason}", stacklevel=3)

class PoseLookup:
    """Hand pose from one camera frame by database lookup (SPEC.md section 1).

    Parameters
    ----------
    database : handsynth.db.Database
        An opened database (see :meth:`open` to open one from a folder).
    options : SearchOptions, keyword-only, optional
        Search constants (the paper's by default).  Not usable with
        :meth:`calibrated`, whose search has no such constants.
    temporal : bool or None, keyword-only
        Score the previous frame's answer first (same answers, often faster).
        The previous answer is the only state; it is a plain int, so sharing
        one instance between threads stays safe (each thread may seed from
        another thread's last answer, which changes no result).  ``None``
        (default): ``True``, and ``False`` for a calibrated lookup (its
        search takes no seed; ``temporal=True`` cannot be calibrated).
    ties : {"mean", "first"} or None, keyword-only
        What to report when several entries match equally well (the same
        smallest ``E``: mostly entries whose features are identical because
        a finger is folded out of the camera's view).  ``"mean"``: the mean
        of their angles and keypoints, the answer with the smallest expected
        error when each is equally likely; ``"first"``: the first entry's,
        as a plain reading of the paper.  ``entry`` is the first either
        way.  ``None`` (default): ``"mean"``, and ``"first"`` with the
        approximate index, which tracks no ties (``ties="mean"`` with it is
        refused).
    approximate : ApproximateIndex, ApproximateOptions or bool, keyword-only, optional
        Search with the approximate (IVF) index instead of the exact search
        (for databases of 10^5-10^6 entries; see
        :mod:`handsynth.estimate._ann`).  ``True`` or options: open the
        index kept next to the database file, building it if needed.

    Raises
    ------
    InvalidInputError
        A value of the wrong type, or a combination that cannot be
        honoured (``ties="mean"`` with `approximate`), naming the options
        and the value received.

    Notes
    -----
    :meth:`calibrated` gives a lookup that matches frames by the pixels
    outside a user's ignore mask, learnt from one open-hand frame
    (:mod:`handsynth.estimate._calibration`, beyond the paper), and reports
    the weighted mean of the entries near the best; it needs the exact
    search and takes no `options` and no ``temporal=True``.
    :meth:`from_open_frame` also chooses the database from that frame.

    Examples
    --------
    >>> lookup = PoseLookup.open("dbs/", shape=HandShape())      # doctest: +SKIP
    >>> est = lookup.estimate(frame)                              # doctest: +SKIP
    >>> est.angles.shape, est.no_hand                             # doctest: +SKIP
    ((20,), False)
    """

    def __init__(self, database: Database, *, options: SearchOptions | None = None,
                 temporal: bool | None = None, ties: str | None = None,
                 approximate=None) -> None:
        if not isinstance(database, Database):
            raise InvalidInputError(
                f"database must be a handsynth.db.Database, got {type(database).__name__}")
        search_options = check_options(options, SearchOptions)
        if temporal is not None and not isinstance(temporal, (bool, np.bool_)):
            raise InvalidInputError(f"temporal must be True, False or None, got {temporal!r}")
        if ties not in (None, "mean", "first"):
            raise InvalidInputError(f"ties must be 'mean', 'first' or None, got {ties!r}")
        approximate_used = approximate is not None and approximate is not False
        if approximate_used and ties == "mean":
            raise InvalidInputError(
                "ties='mean' cannot be honoured by the approximate index (it tracks no ties); "
                "pass ties='first' or leave ties unset")
        self.database = database
        self.options = search_options
        self.temporal = True if temporal is None else bool(temporal)
        self.ties = ties or ("first" if approximate_used else "mean")
        # what the caller chose, for the combinations that calibrated() cannot honour
        self._requested = {"options": options, "temporal": temporal}
        meta = database.meta
        try:
            self.mount = CameraMount(**meta["mount"])
            self.side = meta.get("side", "right")
            self.image_size = int(meta.get("features", {}).get("image_size", 64))
        except (KeyError, TypeError) as exc:
            raise DatabaseError(f"database {database.path} has no usable camera mount in its "
                                f"metadata: {exc}") from None
        self.shape = HandShape(**meta["shape"]) if "shape" in meta else None
        self.tables = SearchTables.from_arrays(
            hlac=database.hlac, sil_bits=database.sil_bits, ridge_bits=database.ridge_bits,
            ridge_area=database.ridge_area)
        self.approximate = self._approximate_index(approximate)
        if self.approximate is None:
            self.tables.prepare()  # the exact search's index, before the first frame
        self._angles = np.asarray(database.angles, dtype=np.float64)
        self._angles.setflags(write=False)
        self._last = -1
        self.calibration: Calibration | None = None
        self._band_areas: np.ndarray | None = None  # masked_band_areas of the calibration

    def calibrated(self, open_frame, *, dilation_px: int = 1,
                   temperature_px: float = 1.0) -> PoseLookup:
        """A lookup of the same database calibrated to a user's open-hand frame.

        Parameters
        ----------
        open_frame : ndarray, shape (H, W) or (H, W, 3)
            The user's hand open and flat (all joint angles 0) through the
            database's camera: a frame as :meth:`estimate` takes.
        dilation_px : int, keyword-only
            Growth of the ignore mask, 4-neighbour steps (0 to 8).
        temperature_px : float, keyword-only
            Entries near the best enter the reported pose with weights
            ``exp(-(X - X_min) / temperature_px)`` (0 to 8 pixels; 0: the
            tied entries only).  With ``ties="first"`` the matched entry's
            own pose is reported.

        Returns
        -------
        PoseLookup
            A new lookup sharing this one's database; this one is unchanged.

        Raises
        ------
        InvalidInputError
            The frame is not an image, is not of the device's width-to-height
            ratio (:meth:`silhouette`) or shows no hand, the database has no
            open-hand entry, or this lookup was made with an option the
            calibrated search cannot honour: the approximate index,
            `options` or ``temporal=True`` (naming it and the value).
        """
        _refuse_for_calibration(approximate=self.approximate, **self._requested)
        user = self.silhouette(open_frame)
        if not user.any():
            raise no_hand_error("open_frame")
        reference = reference_silhouette(self.database)
        out = copy.copy(self)
        out._last = -1
        out.temporal = False  # the masked search takes no seed
        out.calibration = Calibration.from_silhouettes(user, reference, dilation_px=dilation_px,
                                                       temperature_px=temperature_px)
        out._band_areas = masked_band_areas(self.tables.sil_bits, out.calibration)
        out._band_areas.setflags(write=False)  # shared by every thread of the lookup
        return out

    def _approximate_index(self, approximate):
        if approximate is None or approximate is False:
            return None
        from ._ann import ApproximateIndex, ApproximateOptions

        if approximate is True:
            approximate = ApproximateOptions()
        if isinstance(approximate, ApproximateOptions):
            return ApproximateIndex.open(self.database, self.tables, options=approximate)
        if isinstance(approximate, ApproximateIndex):
            approximate.check_matches(self.tables)
            return approximate
        raise InvalidInputError("approximate must be an ApproximateIndex, ApproximateOptions, "
                                f"True or None, got {type(approximate).__name__}")

    @classmethod
    def open(cls, folder, *, shape: HandShape | str | None = None,
             measurements: HandMeasurements | None = None,
             selection: SelectionOptions | None = None, side: str = "right",
             **kwargs) -> PoseLookup:
        """Open the database of a hand from a folder of ``<HandShape.name>.h5`` files.

        Parameters
        ----------
        folder : str or os.PathLike
        shape : HandShape or str, keyword-only, optional
            Use the database of the grid shape nearest to `shape` (or to the
            shape of this :attr:`HandShape.name`).
        measurements : HandMeasurements, keyword-only, optional
            Choose the shape by formulas (1)-(4) (:func:`select_shape`).
            Give `shape` or `measurements`; the standard hand if neither.
        selection : SelectionOptions, keyword-only, optional
            Options of the selection from `measurements`.
        side : {"right", "left"}, keyword-only
            Hand side: the left hand's file is ``<HandShape.name>_left.h5``
            (:func:`handsynth.db.database_path`).
        **kwargs
            Passed to :class:`PoseLookup` (``options``, ``temporal``, ``ties``,
            ``approximate``).

        Raises
        ------
        InvalidInputError
            `folder` is not a folder name (None, a number, ``""``), both
            `shape` and `measurements` are given, `shape` is neither a
            HandShape nor a shape name, or `kwargs` hold an argument
            :class:`PoseLookup` does not take (naming ``PoseLookup.open``),
            before any file is read.
        DatabaseError
            The folder or the chosen database file does not exist.
        DatabaseMismatchError
            The file holds another shape or side than the one asked for
            (:func:`handsynth.db.check_database_hand`).
        """
        folder = check_path(folder, "folder", kind="folder")
        _check_lookup_kwargs(kwargs, "PoseLookup.open")
        if shape is not None and measurements is not None:
            raise InvalidInputError("give shape or measurements, not both")
        if measurements is not None:
            grid = select_shape(measurements, options=selection).shape
        else:
            if isinstance(shape, str):
                shape = HandShape.from_name(shape)
            if shape is not None and not isinstance(shape, HandShape):
                raise InvalidInputError(
                    f"shape must be a HandShape or a shape name, got {type(shape).__name__}")
            grid = (HandShape() if shape is None else shape).nearest_grid()
        path = find_database(folder, grid, side)
        database = open_database(path)
        check_database_hand(database.meta, grid, side, path)
        return cls(database, **kwargs)

    @classmethod
    def personal(cls, folder, *, shape: HandShape | None = None,
                 measurements: HandMeasurements | None = None,
                 selection: SelectionOptions | None = None, mount: CameraMount | None = None,
                 build=None, workers: int | None = None, progress=None,
                 **kwargs) -> PoseLookup:
        """Open the database of exactly this hand's shape, building it first if missing.

        The paper picks the nearest of 81 grid shapes because rendering a
        database took hours.  Here one of 20,448 entries takes about 5 s on
        two cores, so a hand can have its own: on off-grid model hands this
        halves the error of the selected grid database (docs/lookup.md, "The
        paper's experiment").  The file is ``<folder>/<shape.name>.h5``
        (``<shape.name>_left.h5`` for the left hand); a verified existing one
        is reused, one built with other options is rebuilt, one holding
        another shape or side is refused.

        Parameters
        ----------
        folder : str or os.PathLike
            Database folder, created if missing.
        shape : HandShape, keyword-only, optional
            The hand's ratios, rounded to the 0.001 of :attr:`HandShape.name`
            (e.g. :attr:`PhotoMeasurement.shape <handsynth.estimate.PhotoMeasurement.shape>`).
        measurements : HandMeasurements, keyword-only, optional
            Instead of `shape`: the ratios of formulas (1)-(4) from these
            millimetres (:func:`shape_ratios`), without the grid.
        selection : SelectionOptions, keyword-only, optional
            Options of formulas (1)-(4) for `measurements`; by default no
            normalisation (``normalize="none"``), since millimetres give the
            ratios directly.
        mount : CameraMount, keyword-only, optional
            The device; the paper's by default.
        build : handsynth.db.BuildOptions, keyword-only, optional
            Pose set, count, seed, side and render size of the database: the
            paper's 20,448 poses by default.
        workers : int, keyword-only, optional
            Worker processes for a build; all cores by default.
        progress : callable, keyword-only, optional
            Called with :class:`handsynth.db.BuildProgress` while building.
        **kwargs
            Passed to :class:`PoseLookup`.

        Raises
        ------
        InvalidInputError
            Neither or both of `shape` and `measurements`, values of the
            wrong type, or `kwargs` holding an argument :class:`PoseLookup`
            does not take (naming ``PoseLookup.personal``), before anything
            is built.
        DatabaseError
            The database could not be built or read.
        """
        _check_lookup_kwargs(kwargs, "PoseLookup.personal")
        if (shape is None) == (measurements is None):
            raise InvalidInputError("give exactly one of shape or measurements")
        if measurements is not None:
            opts = (SelectionOptions(normalize="none") if selection is None
                    else check_options(selection, SelectionOptions, name="selection"))
            shape = select_shape(measurements, options=opts).ratios
        else:
            shape = check_instance(shape, HandShape, name="shape")
        build = check_options(build, BuildOptions, name="build")
        shape = HandShape.from_name(shape.name)
        summary = build_databases(folder, [shape], as_mount(mount), options=build,
                                  workers=workers, progress=progress)
        _warn_rebuilt(summary)
        database = open_database(summary.paths[0])
        check_database_hand(database.meta, shape, build.side, summary.paths[0])
        return cls(database, **kwargs)

    @classmethod
    def from_open_frame(cls, folder, open_frame, *, mount: CameraMount | None = None,
                        build=None, workers: int | None = None, progress=None, shapes=None,
                        dilation_px: int = 1, temperature_px: float = 1.0,
                        **kwargs) -> PoseLookup:
        """A calibrated lookup from one frame of the user's open, flat hand (beyond the paper).

        Chooses the database shape whose open hand fits the frame best
        (:func:`select_shape_from_frame`), opens its database in `folder`
        (building it first when missing, about 5 s for 20,448 entries on two
        cores) and calibrates it to the frame (:meth:`calibrated`).  On the
        realistic mesh hand this is the most accurate lookup handsynth has
        (docs/lookup.md, "Calibrated lookup").

        Parameters
        ----------
        folder : str or os.PathLike
            Database folder, created if missing.
        open_frame : ndarray, shape (H, W) or (H, W, 3)
            The user's hand open and flat (all joint angles 0) through the
            device camera, as :meth:`estimate` takes it.
        mount : CameraMount, keyword-only, optional
            The device; the paper's by default.
        build : handsynth.db.BuildOptions, keyword-only, optional
            Options of a database that has to be built (the paper's 20,448
            poses by default); its ``side`` is the hand's side.
        workers, progress : keyword-only, optional
            As for :func:`handsynth.db.build_databases`.
        shapes : sequence of HandShape, keyword-only, optional
            Candidate shapes; the 81 grid shapes by default.  The chosen
            one's database is built with its ratios rounded to the 0.001 of
            :attr:`HandShape.name`.
        dilation_px, temperature_px : keyword-only
            As for :meth:`calibrated`.
        **kwargs
            Passed to :class:`PoseLookup`: ``ties`` (``temporal=False`` is
            accepted and changes nothing).

        Raises
        ------
        InvalidInputError
            The frame is not an image, is not of the device's
            width-to-height ratio (:meth:`silhouette`) or shows no hand (what
            stands out covers less than
            :data:`~handsynth.estimate.MIN_HAND_COVERAGE` of it), an
            option is invalid, or `kwargs` hold an argument
            :class:`PoseLookup` does not take (naming
            ``PoseLookup.from_open_frame``) or an option the calibrated
            search cannot honour (``options``, ``temporal=True``,
            ``approximate``), before anything is built.
        DatabaseError
            The database could not be built or read.
        """
        _check_lookup_kwargs(kwargs, "PoseLookup.from_open_frame")
        _refuse_for_calibration(options=kwargs.get("options"),
                                temporal=kwargs.get("temporal"),
                                approximate=kwargs.get("approximate"))
        build = check_options(build, BuildOptions, name="build")
        mount = as_mount(mount)
        check_frame_ratio(open_frame, mount, view=_LOOKUP_VIEW)
        # refuses a frame that shows no hand (a speck) before anything is built
        chosen = select_shape_from_frame(open_frame, mount=mount, side=build.side,
                                         shapes=shapes).shape
        chosen = HandShape.from_name(chosen.name)  # the ratios its file name gives
        summary = build_databases(folder, [chosen], mount, options=build, workers=workers,
                                  progress=progress)
        _warn_rebuilt(summary)
        database = open_database(summary.paths[0])
        check_database_hand(database.meta, chosen, build.side, summary.paths[0])
        lookup = cls(database, **kwargs)
        return lookup.calibrated(open_frame, dilation_px=dilation_px,
                                 temperature_px=temperature_px)

    @classmethod
    def from_rows(cls, rows: dict, *, mount: CameraMount | None = None, shape: HandShape | None = None,
                  side: str = "right", **kwargs) -> PoseLookup:
        """An in-memory lookup from rows of :func:`handsynth.db.render_entries`.

        The rows must have been made with `mount` (the paper's by default).

        Parameters
        ----------
        rows : mapping
            ``angles``, ``hlac``, ``sil_bits``, ``ridge_bits``,
            ``ridge_area`` and ``keypoints`` (metres), checked as
            :func:`handsynth.db.write_database` checks them
            (:func:`handsynth.db.check_rows`).
        mount : CameraMount, keyword-only, optional
        shape : HandShape, keyword-only, optional
            The standard hand by default.
        side : {"right", "left"}, keyword-only
        **kwargs
            Passed to :class:`PoseLookup`.

        Raises
        ------
        InvalidInputError
            A missing key, an array of the wrong shape, dtype or range (NaN
            or out-of-limit angles, keypoints beyond +/-0.32767 m, rows of
            different lengths), or `mount`, `shape` or `side` of the wrong
            type or value; the message names it.  `kwargs` holding an
            argument :class:`PoseLookup` does not take (naming
            ``PoseLookup.from_rows``).
        """
        _check_lookup_kwargs(kwargs, "PoseLookup.from_rows")
        mount = as_mount(mount)
        if shape is not None:
            check_instance(shape, HandShape, name="shape")
        check_side(side)
        arrays = check_rows(rows)
        meta = {"mount": mount.as_dict(), "side": side,
                "shape": (HandShape() if shape is None else shape).as_dict(),
                "features": {"image_size": 64}}
        db = Database(
            path=Path("<memory>"), meta=meta, angles=arrays["angles"], hlac=arrays["hlac"],
            sil_bits=arrays["sil_bits"], ridge_bits=arrays["ridge_bits"],
            ridge_area=arrays["ridge_area"], keypoints_raw=arrays["keypoints"])
        return cls(db, **kwargs)

    def __len__(self) -> int:
        return len(self.tables)

    def silhouette(self, frame: np.ndarray) -> np.ndarray:
        """The 64x64 bool silhouette of `frame` as the database sees it.

        All False when the frame shows no hand: nothing stands out, or the
        kept hand component (:func:`~handsynth.render.preprocess`, after the
        wrist cut) covers less than :data:`~handsynth.estimate.MIN_HAND_COVERAGE`
        (1 %) of the frame's pixels, too little to be a hand (a speck, one
        bright pixel), as for the learnt estimators.  The smallest modelled
        hand in a fist covers about 7 % of the paper's view, so no database
        entry falls under it.

        Raises
        ------
        InvalidInputError
            A frame that is not an image, or whose width-to-height ratio is
            not the database's camera mount's (:func:`check_frame_ratio`:
            it would be stretched).
        """
        check_frame_ratio(frame, self.mount, view=_LOOKUP_VIEW)
        return preprocess(frame, self.mount, side=self.side, size=self.image_size,
                          min_coverage=MIN_HAND_COVERAGE)

    def estimate(self, frame: np.ndarray) -> PoseEstimate:
        """Pose of the hand in one frame.

        Parameters
        ----------
        frame : ndarray, shape (H, W) or (H, W, 3)
            A BGR uint8 camera frame, a grey uint8 frame or a bool mask, of
            any size (at least 8x8) taken by the database's camera mount
            (its width-to-height ratio, within 1 %).

        Returns
        -------
        PoseEstimate
            ``no_hand=True`` (NaN angles) when the frame shows no hand: its
            silhouette is empty, or what stands out covers less than
            :data:`~handsynth.estimate.MIN_HAND_COVERAGE` of the frame
            (:meth:`silhouette`), with or without a calibration.

        Raises
        ------
        InvalidInputError
            A frame that is not an image: not an array, wrong dtype (float,
            NaN...), wrong shape, smaller than 8x8; or a frame whose
            width-to-height ratio is not the device's (a portrait frame, a
            640x480 webcam frame for a 720x480 device), naming its size.
        """
        sil = self.silhouette(frame)
        if not sil.any():
            return PoseEstimate(angles=np.full(len(JOINT_NAMES), np.nan),
                                keypoints=np.full((21, 3), np.nan, np.float32), confidence=0.0,
                                entry=-1, error=float("inf"), low_confidence=True, no_hand=True)
        if self.calibration is not None:
            return self._estimate_calibrated(sil, self.calibration)
        f = extract_features(sil)
        seed = self._last if self.temporal and self._last >= 0 else None
        if self.approximate is not None:
            r = self.approximate.search(f, self.options, seed=seed)
        else:
            r = search(f, self.tables, options=self.options, seed=seed)
        self._last = r.index
        scale = self.options.c3 * max(f.ridge_area, 1)
        conf = float(np.exp(-r.error / scale)) if scale > 0 else float(r.error == 0)
        if r.low_confidence:
            conf *= 0.5
        angles, keypoints = self._pose(r.index, r.tied)
        return PoseEstimate(angles=angles, keypoints=keypoints, confidence=conf,
                            entry=r.index, error=r.error, low_confidence=r.low_confidence,
                            no_hand=False)

    def _estimate_calibrated(self, sil: np.ndarray, calibration: Calibration) -> PoseEstimate:
        m = masked_search(sil, self.tables.sil_bits, calibration,
                          band_areas=self._band_areas)
        angles, keypoints = self._pose(m.index, m.near, m.weights)
        return PoseEstimate(angles=angles, keypoints=keypoints,
                            confidence=1.0 - m.error / max(m.union, 1), entry=m.index,
                            error=float(m.error), low_confidence=False, no_hand=False)

    def _pose(self, index: int, rows: np.ndarray | None,
              weights: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Angles and keypoints reported for a match: entry `index`, or with ``ties="mean"``
        the mean over `rows` (``None``: not tracked), weighted by `weights` if given."""
        if self.ties != "mean" or rows is None or rows.size == 1:
            return self._angles[index].copy(), self.database.keypoints_m(index)
        if weights is None:
            return self._angles[rows].mean(axis=0), self.database.keypoints_m(rows).mean(axis=0)
        keypoints = np.tensordot(weights, self.database.keypoints_m(rows), axes=1)
        return weights @ self._angles[rows], keypoints.astype(np.float32)
