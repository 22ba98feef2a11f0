"""SCoRE: symmetrical centre of rotation estimation (Ehrig et al. 2006).

Ehrig, Taylor, Duda & Heller, "A survey of formal methods for determining
the centre of rotation of ball joints", *J. Biomech.* 39:2798-2809 (2006).
The centre has constant coordinates ``c_U`` and ``c_L`` in both segments and
both may move; in the transmitter frame, for every frame ``i``::

    R_U(i) c_U + t_U(i) = R_L(i) c_L + t_L(i)

stacked over frames into a ``(3n, 6)`` linear system solved in the least
squares sense.  Multiplying each frame's residual by ``R_U(i)^T`` gives the
O'Brien et al. (2000) system with the same residual norm, so on the same
frames the two minimise the same quantity; they differ in the treatment of a
rank-deficient (hinge) system.  SCoRE assumes a ball joint and solves the
full system (machine-precision cut-off): on a pure hinge its centre is then
fixed along the axis by noise alone, which :func:`handsynth.sensors.evaluate`
shows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._checks import check_number
from ._estimators import _Estimator, _Frames

__all__ = ["ScoreEstimator"]


@dataclass(frozen=True, kw_only=True)
class ScoreEstimator(_Estimator):
    """SCoRE joint centre (Ehrig et al. 2006), in the transmitter frame.

    Parameters
    ----------
    rcond : float or None
        Singular-value cut-off of :func:`numpy.linalg.lstsq`; ``None`` is
        machine precision (the plain least-squares solution of the paper).

    Other parameters are those of every estimator (``frames``,
    ``axis_filter``, ``min_rom_deg``, ``min_frames``).
    """

    rcond: float | None = None

    name = "score"

    def __post_init__(self) -> None:
        super().__post_init__()
        if self.rcond is not None:
            self._set("rcond", check_number(self.rcond, "rcond", minimum=0.0, below=1.0))

    def _solve(self, f: _Frames):
        rec = f.recording
        ru, rl = rec.rotations[:, 0], rec.rotations[:, 1]
        a = np.concatenate([ru, -rl], axis=2).reshape(-1, 6)  # (3n, 6)
        b = (rec.positions[:, 1] - rec.positions[:, 0]).reshape(-1)
        x, *_ = np.linalg.lstsq(a, b, rcond=self.rcond)
        resid = (a @ x - b).reshape(-1, 3)
        return x[:3], x[3:], float(np.sqrt((resid**2).sum(axis=1).mean()) * 1e3)
