import json

import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.sensors.imu._eval import HELDOUT, TUNING, SimConfig, evaluate, make_filter


def test_configs_differ_in_what_the_filters_did_not_see():
    assert TUNING.noise.label != HELDOUT.noise.label
    assert HELDOUT.skin is not None and HELDOUT.tilt_sd_deg > 0 and HELDOUT.noise.disturbances
    assert HELDOUT.shape != TUNING.shape
    p = HELDOUT.placement()
    assert len(p.tilts_deg) == 20 and len(p.offsets_mm) == 20


def test_unknown_filter_is_named():
    with pytest.raises(InvalidInputError, match="unknown filter 'kalman9'"):
        make_filter("kalman9")
    with pytest.raises(InvalidInputError, match="filter4 needs a link model"):
        make_filter("filter4")


@pytest.mark.slow
def test_small_evaluation_is_json_and_has_baselines():
    cfg = SimConfig("small", seed=3)
    rep = evaluate(cfg, durations=(8.0,), elbows=("fixed",), filters=("constant", "raw", "filter4"),
                   grasps=False)
    json.dumps(rep)
    s = rep["summary"]
    assert s["raw"]["orientation_mean_deg"] < s["constant"]["orientation_mean_deg"]
    assert s["filter4"]["orientation_mean_deg"] < s["constant"]["orientation_mean_deg"]
    assert np.isfinite(s["filter4"]["fingertip_mean_rmse_mm"])
    v = rep["vectors"]
    assert v["rotation_method"]["median_mm"] < v["baseline_zero_vector"]["median_mm"]
    # one trial summarised alone gives evaluate's figures for it
    from handsynth.sensors.imu._eval import _calibrate, evaluate_trial, free_trials
    from handsynth.sensors.imu._model import ImuHand

    _, calib, sensor_cal = _calibrate(cfg, cfg.placement())
    (_, _, rec), = free_trials(cfg, ImuHand(cfg.shape, placement=cfg.placement()), durations=(8.0,),
                               elbows=("fixed",))
    one = evaluate_trial(sensor_cal.apply(rec), calib, filters=("constant", "raw", "filter4"))
    assert one == s
    with pytest.raises(InvalidInputError, match="unknown filter 'kalman9'"):
        evaluate_trial(rec, calib, filters=("kalman9",))
    with pytest.raises(InvalidInputError, match="needs a simulated recording"):
        evaluate_trial(rec.subset(rec.sensors), calib)


# --------------------------------------------------------------------------- plots


def _plot_args():
    t = np.linspace(0.0, 4.0, 50)
    chains = {label: {"index": np.cumsum(np.full((4, 3), s), axis=0)}
              for label, s in (("truth", 0.02), ("filter4", 0.021))}
    return t, {"raw": 1.0 + t, "filter4": 0.5 + 0.1 * t}, chains


def test_plots_are_pngs_written_whole_and_a_bad_path_is_an_output_error(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    from handsynth.errors import OutputError
    from handsynth.sensors.imu import plot_orientation_error, plot_stick_figure

    t, errors, chains = _plot_args()
    a = plot_orientation_error(t, errors, tmp_path / "err.png", title="t")
    b = plot_stick_figure(chains, tmp_path / "stick.png", title="t")
    assert (a, b) == (tmp_path / "err.png", tmp_path / "stick.png")
    for p in (a, b):
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["err.png", "stick.png"]  # no .tmp-
    # a path under a file: the project's output error naming the path, not FileNotFoundError
    (tmp_path / "afile").write_text("")
    bad = tmp_path / "afile" / "p.png"
    with pytest.raises(OutputError, match=r"cannot write the plot '.*afile/p\.png'"):
        plot_orientation_error(t, errors, bad)
    with pytest.raises(OutputError, match=r"cannot write the plot '.*afile/p\.png'"):
        plot_stick_figure(chains, bad)
    with pytest.raises(OutputError, match="never replaces an input"):
        plot_stick_figure(chains, tmp_path / "in.png", inputs=[tmp_path / "in.png"])

    # a failure half-way through the PNG leaves neither a half-written file nor a temporary one
    def half_then_fail(self, f, **kw):
        f.write(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", half_then_fail)
    with pytest.raises(OutputError, match=r"cannot write the plot .*no space left"):
        plot_orientation_error(t, errors, tmp_path / "half.png")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile", "err.png", "stick.png"]


def test_plots_leave_the_callers_matplotlib_backend_and_pyplot_alone(tmp_path):
    # _plot called matplotlib.use("Agg") and drew through pyplot's global state
    import subprocess
    import sys

    code = f"""
import sys
import matplotlib
matplotlib.use("svg")
import numpy as np
from handsynth.sensors.imu import plot_orientation_error, plot_stick_figure
t = np.linspace(0.0, 1.0, 10)
plot_orientation_error(t, {{"raw": 1.0 + t}}, {str(tmp_path / "e.png")!r})
plot_stick_figure({{"truth": {{"index": np.eye(3)}}}}, {str(tmp_path / "s.png")!r})
assert "matplotlib.pyplot" not in sys.modules, "pyplot was imported"
assert matplotlib.get_backend() == "svg", matplotlib.get_backend()
print("ok")
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0 and res.stdout.strip() == "ok", res.stderr
    assert (tmp_path / "e.png").read_bytes()[:4] == b"\x89PNG"
