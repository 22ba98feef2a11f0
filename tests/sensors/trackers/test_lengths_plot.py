import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.trackers import (
    NO_NOISE,
    SEGMENT_NAMES,
    AxisAngleFilter,
    FlexionMotion,
    OBrienEstimator,
    SensorMount,
    plot_axis_histogram,
    segment_length_mm,
    segment_lengths_mm,
    simulate_recording,
)


def test_middle_phalanx_length_from_pip_and_dip():
    mount = SensorMount(pitch_deg=10.0)  # same sensor on index_middle in both trials
    kw = dict(model="hinge", noise=NO_NOISE, geometry_source="table",
              motion=FlexionMotion(duration_s=4.0, wobble_deg=0.0), seed=0)
    pip = simulate_recording("index_pip", lower_mount=mount, **kw)
    dip = simulate_recording("index_dip", upper_mount=mount, **kw)
    rp, rd = OBrienEstimator().estimate(pip), OBrienEstimator().estimate(dip)
    true = dip.metadata["upper_length_mm"]
    assert segment_length_mm(rp, rd) == pytest.approx(true, abs=0.01)
    lengths = segment_lengths_mm([rp, rd])
    assert lengths.shape == (14,) and len(SEGMENT_NAMES) == 14
    i = SEGMENT_NAMES.index("index_middle")
    assert lengths[i] == pytest.approx(true, abs=0.01)
    assert np.isnan(np.delete(lengths, [i, SEGMENT_NAMES.index("index_distal")])).all()
    with pytest.raises(InvalidInputError, match="not the distal"):
        segment_length_mm(rd, rp)


def test_histogram_png(tmp_path, finger_rec):
    f = AxisAngleFilter(lateral_axis="recording").apply(finger_rec)
    out = plot_axis_histogram(f, tmp_path / "h.png", title="t")
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
