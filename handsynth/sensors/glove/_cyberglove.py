"""Reader of 22-sensor CyberGlove-style joint-angle exports (CSV).

A CyberGlove (CyberGlove Systems; Immersion CyberTouch in seed 004) has 22
bend sensors: per finger MCP, PIP and DIP (thumb: rotation, MCP, IP), the
abduction between neighbouring fingers and of the thumb, palm arch and
wrist flexion and abduction.  Public grasp datasets publish calibrated
angles from such gloves as CSV, one row per sample.  This reader turns such
a file into the 20 canonical angles of :data:`handsynth.models.JOINT_NAMES`
(for synergies, :func:`fit_synergies`):

* flexions map one to one; thumb rotation (across the palm) is taken as
  ``thumb_cmc_flex`` and thumb abduction as ``thumb_cmc_abd`` (an
  approximation: the glove's sensors do not sit on anatomical axes);
* the glove measures abduction *between* fingers, the hand model per
  finger; the middle finger is taken as 0, so ``index_mcp_abd`` = the
  index-middle angle, ``ring_mcp_abd`` = -(ring-middle) and
  ``little_mcp_abd`` = ring - (little-ring) (abduction is positive toward
  the thumb);
* palm arch and the wrist are not part of the hand model and are dropped.

The column names are this project's (:data:`CYBERGLOVE_COLUMNS`); a file
with a header is read by name, a file without one in that order; pass
`columns` for an export in another order.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np

from ..._csv import column_index, read_rows, reads_as_number
from ...errors import RecordingError
from ...models import JOINT_LIMITS_DEG, JOINT_NAMES
from ._models import GloveWarning

__all__ = ["CYBERGLOVE_COLUMNS", "read_cyberglove_csv"]

#: The 22 sensors, in the order a header-less file is read.
CYBERGLOVE_COLUMNS: tuple[str, ...] = (
    "thumb_rotation", "thumb_mcp", "thumb_ip", "thumb_abduction",
    "index_mcp", "index_pip", "index_dip",
    "middle_mcp", "middle_pip", "middle_dip", "middle_index_abduction",
    "ring_mcp", "ring_pip", "ring_dip", "ring_middle_abduction",
    "little_mcp", "little_pip", "little_dip", "little_ring_abduction",
    "palm_arch", "wrist_flexion", "wrist_abduction",
)

_DIRECT = {
    "thumb_cmc_flex": "thumb_rotation", "thumb_cmc_abd": "thumb_abduction",
    "thumb_mcp_flex": "thumb_mcp", "thumb_ip_flex": "thumb_ip",
    **{f"{f}_{j}_flex": f"{f}_{j}" for f in ("index", "middle", "ring", "little")
       for j in ("mcp", "pip", "dip")},
}

#: Largest |angle| (deg) a cell can hold: beyond, it is corrupt (the synergies' covariance
#: would overflow).
_MAX_ANGLE_DEG = 720.0
#: Share of values beyond the joint limits (by more than 30 deg) above which
#: the file is refused as being in other units.
_UNIT_SUSPECT_SHARE = 0.05


def read_cyberglove_csv(path, *, units: str = "deg",
                        columns: tuple[str, ...] | None = None) -> np.ndarray:
    """Canonical joint angles from a 22-sensor glove export.

    Parameters
    ----------
    path : str or Path
        CSV, comma-separated; an optional header line of the names in
        :data:`CYBERGLOVE_COLUMNS`, in any case, with spaces, dots or dashes
        for ``_`` and ``pinky`` for ``little`` (``Thumb Rotation``,
        ``PINKY_MCP``); extra columns such as a time stamp are ignored.
    units : {"deg", "rad"}, keyword-only
        Unit of the angles in the file.
    columns : tuple of str, keyword-only
        Names of the columns of a header-less file, in file order; default
        :data:`CYBERGLOVE_COLUMNS`.

    Returns
    -------
    ndarray, shape (N, 20), float64, deg
        Canonical order; a row with an empty or NaN cell is NaN throughout.

    Raises
    ------
    RecordingError
        No such file, no data, a missing column, a cell that is not a number
        or is infinite or beyond +-720 deg (file, line and column named), or
        values that look like another unit.

    Warns
    -----
    GloveWarning
        Rows with an empty or NaN cell (counted, named by file line); a
        sensor that reads the same in every complete row (of 30 or more).
    """
    if units not in ("deg", "rad"):
        raise RecordingError(f"units must be 'deg' or 'rad', got {units!r}")
    path = Path(path)
    content = read_rows(path, what="glove export")
    rows = content.rows
    if not rows:
        raise RecordingError(f"{path}: empty file")
    first = rows[0]
    if all(reads_as_number(c) for c in first):
        names = list(columns or CYBERGLOVE_COLUMNS)
        body, lines = rows, content.lines
    else:  # an export's own spelling: "Thumb MCP", "INDEX_PIP", "pinky_dip"
        names, body, lines = [_canonical(c) for c in first], rows[1:], content.lines[1:]
    missing = [c for c in CYBERGLOVE_COLUMNS[:19] if c not in names]
    if missing:
        got = "" if all(reads_as_number(c) for c in first) else \
            f" (its header: {', '.join(first[:8])}{', ...' if len(first) > 8 else ''})"
        raise RecordingError(f"{path}: missing column(s) {', '.join(missing)}; expected the "
                             f"names of CYBERGLOVE_COLUMNS{got}")
    if not body:
        raise RecordingError(f"{path}: no data rows")
    col = column_index(names, path=path, line=None if body is rows else content.lines[0])
    scale = 180.0 / np.pi if units == "rad" else 1.0
    raw = np.empty((len(body), len(CYBERGLOVE_COLUMNS[:19])))
    for i, (r, line) in enumerate(zip(body, lines)):
        while len(r) > len(names) and r[-1] == "":  # a trailing delimiter
            r = r[:-1]
        if len(r) != len(names):
            raise RecordingError(f"{path}, line {line}: {len(r)} fields, expected "
                                 f"{len(names)}" + ("" if body is not rows else
                                                    " (no header: the columns of "
                                                    "CYBERGLOVE_COLUMNS)"))
        for k, name in enumerate(CYBERGLOVE_COLUMNS[:19]):
            cell = r[col[name]]
            if cell == "" or cell.lower() == "nan":
                raw[i, k] = np.nan
                continue
            try:
                v = float(cell) * scale
            except ValueError:
                raise RecordingError(f"{path}, line {line}: {name} is {cell!r}, not a "
                                     "number") from None
            if not np.isfinite(v) or abs(v) > _MAX_ANGLE_DEG:
                hint = "; is the file in degrees? pass units='deg' (--synergy-units deg)" \
                    if units == "rad" and np.isfinite(v) else ""
                raise RecordingError(f"{path}, line {line}: {name} is {cell!r}"
                                     f"{' rad' if units == 'rad' else ''}, beyond any joint "
                                     f"angle (|angle| <= {_MAX_ANGLE_DEG:g} deg){hint}")
            raw[i, k] = v
    g = dict(zip(CYBERGLOVE_COLUMNS[:19], raw.T))
    out = np.empty((len(body), len(JOINT_NAMES)))
    for joint, sensor in _DIRECT.items():
        out[:, JOINT_NAMES.index(joint)] = g[sensor]
    ring = -g["ring_middle_abduction"]
    out[:, JOINT_NAMES.index("index_mcp_abd")] = g["middle_index_abduction"]
    out[:, JOINT_NAMES.index("middle_mcp_abd")] = 0.0
    out[:, JOINT_NAMES.index("ring_mcp_abd")] = ring
    out[:, JOINT_NAMES.index("little_mcp_abd")] = ring - g["little_ring_abduction"]
    gaps = np.isnan(out).any(axis=1)
    out[gaps] = np.nan
    _check_units(out, path, units)
    _warn_stuck(raw[~gaps], path)
    if gaps.any():
        idx = np.flatnonzero(gaps)
        at = f"at line {lines[idx[0]]}" if idx.size == 1 else \
            "first at lines " + ", ".join(str(lines[r]) for r in idx[:5])
        warnings.warn(f"{path}: {idx.size} of {len(body)} rows have an empty or NaN cell "
                      f"({at}); their postures are NaN (left out of synergies)", GloveWarning, stacklevel=2)
    return out



def _canonical(name: str) -> str:
    """A header cell as a name of :data:`CYBERGLOVE_COLUMNS` where it spells one in another
    case, with spaces, dots or dashes for ``_``, or ``pinky`` for ``little``."""
    loose = re.sub(r"[ .-]+", "_", name.strip().lower())
    loose = re.sub(r"\bpink(?:y|ie)(?=_|$)", "little", loose)
    return loose if loose in CYBERGLOVE_COLUMNS else name


#: Rows from which a column that never changes is taken for a sensor stuck or unplugged.
_STUCK_MIN_ROWS = 30


def _warn_stuck(raw: np.ndarray, path: Path) -> None:
    """Warn about sensors that read the same in every complete row: the synergies would
    learn that the joint never moves."""
    if len(raw) < _STUCK_MIN_ROWS:
        return
    stuck = [CYBERGLOVE_COLUMNS[k] for k in np.flatnonzero(np.ptp(raw, axis=0) == 0)]
    if stuck:
        warnings.warn(f"{path}: {', '.join(stuck)} read(s) {raw[0, CYBERGLOVE_COLUMNS.index(stuck[0])]:g}"
                      f" in all {len(raw)} complete rows (a sensor stuck or unplugged?); the "
                      "synergies learn that joint as never moving", GloveWarning, stacklevel=3)


def _check_units(angles: np.ndarray, path: Path, units: str) -> None:
    ok = angles[~np.isnan(angles).any(axis=1)]
    if not len(ok):
        raise RecordingError(f"{path}: every row has an empty or NaN cell")
    if units == "deg" and len(ok) > 1 and np.abs(ok).max() <= np.pi and ok.std() > 0:
        raise RecordingError(f"{path}: every angle lies within +/-{np.pi:.4f}; is the file in "
                             "radians? pass units='rad' (--synergy-units rad)")
    beyond = (ok < JOINT_LIMITS_DEG[:, 0] - 30) | (ok > JOINT_LIMITS_DEG[:, 1] + 30)
    share = beyond.mean(axis=0)
    worst = int(np.argmax(share))
    if share[worst] > _UNIT_SUSPECT_SHARE:
        hint = "radians? pass units='rad' (--synergy-units rad)" if units == "deg" else \
            "degrees? pass units='deg' (--synergy-units deg)"
        raise RecordingError(
            f"{path}: {100 * share[worst]:.0f} % of {JOINT_NAMES[worst]} values lie more than "
            f"30 deg outside its limits (e.g. {ok[beyond[:, worst], worst][0]:.4g} deg); "
            f"is the file in {hint}")
