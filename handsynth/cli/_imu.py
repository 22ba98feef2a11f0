"""``handsynth imu``: IMU finger tracking (simulated evaluation, recordings, BROAD)."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import click

from .._io import check_outputs, make_folder, write_json
from ._hand import shape_option
from ._main import cli, input_name

_TRACK_FILTERS = ("raw", "filter1", "gated", "vqf", "vqf_online", "madgwick", "mahony", "ahrs_ekf",
                  "constant")
_CHAIN_FILTERS = ("filter4", "filter4b")  # need the link model of a calibration


#: ``--no-sensor-calibration`` of the commands that apply a calibration file to readings.
_no_sensor_calibration = click.option(
    "--no-sensor-calibration", is_flag=True,
    help="Do not apply the calibration file's accelerometer/gyro/magnetometer corrections "
         "(for readings already corrected).")


def _unit_options(f):
    f = click.option("--mag-axes", metavar="AXES", default=None,
                     help="The accelerometer's axes the magnetometer columns x, y, z hold, as "
                          "a warning names them: y,x,-z for an MPU-9250's AK8963 [default: "
                          "x,y,z].")(f)
    f = click.option("--gyr-axes", metavar="AXES", default=None,
                     help="The accelerometer's axes the gyro columns x, y, z hold (a logger's "
                          "convention), as a warning names them, e.g. x,-y,z [default: x,y,z].")(f)
    f = click.option("--bridge-lost", is_flag=True,
                     help="Fill in samples the logger lost (a sensor repeating its last "
                          "reading for 0.1 s or more, zeros, empty cells) from the other "
                          "sensors' readings, up to 0.5 s (--bridge-max); without it such "
                          "a recording is refused.")(f)
    f = click.option("--bridge-max", "bridge_max_s", type=float, default=None, metavar="SECONDS",
                     help="Longest stretch --bridge-lost fills in, s [default: 0.5]; longer "
                          "ones read further off (held-out, a sensor's 1-s hold bridged: worst "
                          "segment 3.6-4.3 deg against 2.8-3.2 as recorded; 2 s: 5.5-8.5).")(f)
    f = click.option("--gyr-range", "gyr_range_dps", type=float, default=2000.0, show_default=True,
                     help="Gyro full-scale range, deg/s (saturation check).")(f)
    f = click.option("--acc-range", "acc_range_g", type=float, default=16.0, show_default=True,
                     help="Accelerometer full-scale range, g (saturation check).")(f)
    f = click.option("--rate", "rate_hz", type=float, default=None,
                     help="Sampling rate, Hz (default: from the time column).")(f)
    f = click.option("--mag-units", type=click.Choice(("uT", "mT", "G", "nT")), default="uT",
                     show_default=True)(f)
    f = click.option("--gyr-units", type=click.Choice(("rad/s", "deg/s")), default="rad/s",
                     show_default=True)(f)
    f = click.option("--acc-units", type=click.Choice(("m/s2", "g", "mg")), default="m/s2",
                     show_default=True)(f)
    return f


def _read(recording, *, acc_units, gyr_units, mag_units, rate_hz, bridge_lost, bridge_max_s,
          gyr_axes, mag_axes):
    """The CSV recording read, its gyro and magnetometer axes read as `gyr_axes`, `mag_axes`
    (``--gyr-axes``, ``--mag-axes``), the samples it lost filled in when `bridge_lost` (with
    a warning)."""
    import math

    from ..errors import InvalidInputError
    from ..sensors.imu import MAX_BRIDGE_S, parse_axes, read_imu_csv, with_axes
    from ..sensors.imu import bridge_lost as bridge

    if bridge_max_s is not None:
        if not bridge_lost:
            raise InvalidInputError("--bridge-max needs --bridge-lost")
        if not (math.isfinite(bridge_max_s) and bridge_max_s > 0):
            raise InvalidInputError(f"--bridge-max must be a number of seconds > 0, got "
                                    f"{bridge_max_s:g}")
    for flag, axes in (("--gyr-axes", gyr_axes), ("--mag-axes", mag_axes)):
        if axes is not None:
            parse_axes(axes, name=flag)
    rec = read_imu_csv(recording, acc_units=acc_units, gyr_units=gyr_units, mag_units=mag_units,
                       rate_hz=rate_hz)
    if mag_axes is not None and rec.mag is None:
        raise InvalidInputError(f"--mag-axes {mag_axes} given for {recording}, which has no "
                                "magnetometer columns")
    rec = with_axes(rec, gyr=gyr_axes, mag=mag_axes)
    if bridge_lost:
        limit = MAX_BRIDGE_S if bridge_max_s is None else bridge_max_s
        rec, bridged = bridge(rec, max_s=limit, source=str(recording))
        for h in bridged:
            beyond = (f" (longer than the {MAX_BRIDGE_S:g} s bridged by default: that sensor "
                      "reads further off)" if h.duration_s > MAX_BRIDGE_S else "")
            click.echo(f"handsynth: warning: {recording}: bridged: {h.describe()}{beyond}",
                       err=True)
    return rec


def _write_table(path, header, table, *, inputs=()) -> None:
    import numpy as np

    from .._io import atomic_open

    with atomic_open(path, "w", what="CSV file", inputs=inputs) as f:
        f.write(",".join(header) + "\n")
        # times to the microsecond (epoch stamps keep their fraction), the rest 8 digits
        np.savetxt(f, table, delimiter=",", fmt=["%.6f"] + ["%.8g"] * (table.shape[1] - 1))


def _unique_keys(pairs) -> dict:
    """A JSON object's pairs as a dict, refusing a key given twice (the last would win)."""
    out: dict = {}
    for key, value in pairs:
        if key in out:
            raise ValueError(f"label {key!r} is given twice")
        out[key] = value
    return out


def _full_scale(acc_range_g, gyr_range_dps) -> dict:
    """check_recording's full-scale arguments from --acc-range (g) and --gyr-range (deg/s)."""
    import math

    from ..errors import InvalidInputError
    from ..sensors.imu import GRAVITY_MPS2

    # beyond any MEMS part's range (high-g accelerometers reach 400 g, gyros 4,000 deg/s):
    # a larger figure would only switch the saturation check off without a word
    for flag, v, top in (("--acc-range", acc_range_g, 1000.0),
                         ("--gyr-range", gyr_range_dps, 50000.0)):
        if not (math.isfinite(v) and 0 < v <= top):
            raise InvalidInputError(f"{flag} must be a number > 0 and <= {top:g}, got {v!r}")
    return {"acc_full_scale": acc_range_g * GRAVITY_MPS2,
            "gyr_full_scale": math.radians(gyr_range_dps)}


def _filters(values, allowed, *, default=None):
    """The filters named by the --filter values (`default`, else every one `allowed`, when
    none is given)."""
    from ..errors import InvalidInputError

    names = tuple(dict.fromkeys(v.strip() for item in values for v in item.split(",") if v.strip()))
    if values and not names:
        raise InvalidInputError(f"--filter {values[0]!r} names no filter; expected one or more of "
                                f"{', '.join(allowed)}")
    for n in names:
        if n not in allowed:
            raise InvalidInputError(f"unknown filter {n!r}; expected one of {', '.join(allowed)}")
    return names or (allowed if default is None else default)


@cli.group()
def imu() -> None:
    """IMU finger tracking: 20 MEMS IMUs from the elbow to the fingertips (seed 003)."""


@imu.command("eval")
@click.option("--config", "config_name", type=click.Choice(("heldout", "tuning")),
              default="heldout", show_default=True,
              help="Simulator configuration (heldout: not used for tuning).")
@click.option("--seed", type=int, default=None,
              help="Another draw of the configuration: its devices, mounting errors and "
                   "motions from this seed [default: the configuration's own, heldout 1, "
                   "tuning 0].")
@click.option("--filter", "filters", multiple=True,
              help="Filter(s) to run, comma-separated or repeated (default: all).")
@click.option("--duration", "durations", type=float, multiple=True,
              help="Trial length(s), s (default 15 and 30).")
@click.option("--elbow", "elbows", type=click.Choice(("fixed", "moving")), multiple=True,
              help="Elbow condition(s) (default both).")
@click.option("--no-grasps", is_flag=True, help="Skip the grasp classification.")
@click.option("--no-sensor-calibration", is_flag=True,
              help="Leave the trials uncorrected (the accelerometer/gyro/magnetometer "
                   "calibration is applied to every trial by default).")
@click.option("--no-plate-fusion", is_flag=True,
              help="Keep each forearm plate sensor's own attitude (by default the three are "
                   "fused into one after every filter).")
@click.option("--six-axis", is_flag=True,
              help="Read every recording without its magnetometers (6-axis sensors; the "
                   "filters that observe the compass are left out).")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write the full report as JSON.")
@click.option("--plots", "plot_dir", type=click.Path(file_okay=False),
              help="Write orientation_error.png and stick_figure.png (last trial) here.")
def eval_(config_name, seed, filters, durations, elbows, no_grasps, no_sensor_calibration,
          no_plate_fusion, six_axis, json_out, plot_dir) -> None:
    """Reproduce the thesis' tables on simulated data, beside trivial baselines."""
    from ..errors import InvalidInputError, OutputError
    from ..sensors.imu import (
        COMPASS_FILTERS,
        FILTERS,
        HELDOUT,
        TUNING,
        evaluate,
        plot_orientation_error,
        plot_stick_figure,
    )

    # the plots' folder is made and checked before the evaluation's minutes, not after;
    # never where the JSON file goes
    if json_out and plot_dir and Path(json_out).resolve() == Path(plot_dir).resolve():
        raise OutputError(f"--json and --plots name the same path {json_out!r}: choose a file "
                          "for the JSON and a folder for the plots")
    check_outputs([("--json", json_out)])
    plots = make_folder(plot_dir, what="--plots folder", writable=True) if plot_dir else None
    check_outputs([("--json", json_out),
                   *((("--plots", plots / name) for name in ("orientation_error.png",
                                                               "stick_figure.png")) if plots else ())])
    if seed is not None and seed < 0:
        raise InvalidInputError(f"--seed must be a seed >= 0, got {seed}")
    for d in durations:
        if not 6.0 <= d <= 600.0:  # nan fails too
            raise InvalidInputError(f"--duration must be within [6, 600] s (2 s still, 2 s of "
                                    f"the aligning rotation, then the motion), got {d}")
    config = HELDOUT if config_name == "heldout" else TUNING
    if seed is not None:
        config = dataclasses.replace(config, seed=seed)
    series: dict = {}
    rep = evaluate(config, durations=durations or (15.0, 30.0), elbows=elbows or ("fixed", "moving"),
                   filters=_filters(filters, FILTERS, default=tuple(
                       f for f in FILTERS if not (six_axis and f in COMPASS_FILTERS))),
                   grasps=not no_grasps, sensor_calibration=not no_sensor_calibration,
                   plate_fusion=not no_plate_fusion, series=series, six_axis=six_axis)
    if json_out:
        write_json(json_out, rep)  # a NaN error becomes null
    if plots:
        out = plots
        last = rep["trials"][-1]
        what = f"{config.label}, {last['duration_s']:g} s, elbow {last['elbow']}"
        plot_orientation_error(series["t"], series["error"], out / "orientation_error.png",
                               title=f"orientation error ({what})")
        keep = {k: v for k, v in series["chains"].items() if k in ("truth", "filter4", "raw", "vqf")}
        plot_stick_figure(keep, out / "stick_figure.png",
                          title=f"side view at t = {series['chain_time_s']:.2f} s ({what})")
    click.echo(f"config {config.label}: orientation RMSE per segment over the motion, deg")
    click.echo(f"{'filter':<10}{'mean':>7}{'worst':>7}{'distal':>8}{'joint':>7}{'tip mm':>8}"
               f"{'tip/wrist':>10}")
    for name, s in rep["summary"].items():
        click.echo(f"{name:<10}{s['orientation_mean_deg']:7.2f}{s['orientation_worst_segment_deg']:7.2f}"
                   f"{s['orientation_distal_mean_deg']:8.2f}{s['joint_angle_mean_rmse_deg']:7.2f}"
                   f"{s['fingertip_mean_rmse_mm']:8.1f}{s['fingertip_from_wrist_mean_rmse_mm']:10.1f}")
    v = rep["vectors"]
    click.echo("sensor-to-joint vectors, median error mm: "
               + ", ".join(f"{k} {v[k]['median_mm']:.1f}" for k in
                           ("rotation_method", "least_squares_seel", "baseline_standard_hand",
                            "baseline_zero_vector")))


@imu.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@click.option("--segments", "segments_path", type=click.Path(dir_okay=False), required=True,
              help='JSON {"static": [0, 2], "elbow_flex": [2, 9.5], ...}: the labelled '
                   "calibration rotations, seconds; with static poses \"acc_pose_0\" .. "
                   "(nine or more with the static start) the accelerometers and gyros are "
                   "calibrated first.")
@_unit_options
@click.option("--out", "out_path", type=click.Path(dir_okay=False), required=True,
              help="Calibration JSON (link model, link frames, zero pose).")
@click.option("--side", type=click.Choice(("right", "left")), default="right", show_default=True,
              help="The hand the sensors are on; 'track' reads its joint angles as that hand's.")
@click.option("--hinge-centres", type=click.Choice(("plane", "thesis")), default="plane",
              show_default=True,
              help="Where along its axis a one-axis joint's centre is put: nearest the centre of "
                   "the joint its direction is paired with (plane), or where eq. 3.2 puts it "
                   "(thesis, for reproduction).")
def calibrate(recording, segments_path, acc_units, gyr_units, mag_units, rate_hz, acc_range_g,
              gyr_range_dps, bridge_lost, bridge_max_s, gyr_axes, mag_axes, out_path, side,
              hinge_centres) -> None:
    """Sensor-to-joint vectors, link vectors and link frames from a calibration RECORDING."""
    from ..errors import RecordingError
    from ..sensors.imu import calibrate as run_calibration
    from ..sensors.imu import check_recording, segments_from_seconds

    inputs = (recording, segments_path)
    check_outputs([("--out", out_path)], inputs=inputs)
    full_scale = _full_scale(acc_range_g, gyr_range_dps)
    rec = _read(recording, acc_units=acc_units, gyr_units=gyr_units, mag_units=mag_units,
                rate_hz=rate_hz, bridge_lost=bridge_lost, bridge_max_s=bridge_max_s,
                gyr_axes=gyr_axes, mag_axes=mag_axes)
    try:
        spans = json.loads(Path(segments_path).read_text(), object_pairs_hook=_unique_keys)
    except (OSError, ValueError) as exc:  # JSON and text decoding errors are ValueErrors
        raise RecordingError(f"{segments_path}: cannot read the segments JSON ({exc})") from None
    rec = dataclasses.replace(rec, segments=segments_from_seconds(spans, rec.rate_hz, rec.n,
                                                                  source=str(segments_path)))
    # the static poses' sensor calibration first: the magnetometers' field strength is
    # judged as it corrects them (their own hard and soft iron are no disturbance)
    sensor_cal = _static_pose_calibration(rec)
    for w in check_recording(rec, source=str(recording), sensor_calibration=sensor_cal,
                             **full_scale):
        click.echo(f"handsynth: warning: {w}", err=True)
    cal = run_calibration(rec, side=side, source=str(recording),
                          sensor_calibration=True if sensor_cal is None else sensor_cal,
                          hinge_plane=hinge_centres == "plane")
    cal.save(out_path, inputs=inputs)
    lengths = ", ".join(f"{a}->{b} {1e3 * float((v @ v) ** 0.5):.0f} mm"
                        for (s, a, b), v in cal.model.links.items() if s.startswith("index"))
    click.echo(f"calibrated {len(cal.sensors)} sensors of a {side} hand -> {out_path}; "
               f"index links: {lengths}")
    sc = cal.sensor_calibration
    what = "accelerometer/gyro/magnetometer" if rec.has_mag else \
        "accelerometer/gyro (6-axis sensors, no magnetometer)"
    click.echo(f"{what} calibration: " + (
        "none (fewer than 8 static poses acc_pose_<k> in the segments)" if sc is None else
        f"{len(sc.sensors)} sensors, largest accelerometer residual "
        f"{float(sc.acc_residual_mps2.max()):.3f} m/s^2" + (
            f", largest magnetometer residual {float(sc.mag_residual.max()):.2%}"
            if sc.mag_residual is not None else "") + " (stored; 'track' applies it)"))


def _static_pose_calibration(rec):
    """The sensor calibration of `rec`'s static poses (``acc_pose_<k>``), or None with too
    few of them or where its fit fails: fitted before the recording is checked, so whatever
    stops it here is left to ``check_recording`` and ``calibrate``, which name it."""
    import warnings

    from ..sensors.imu import fit_sensor_calibration

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # a fit that warns: calibrate refits it and says so
            return fit_sensor_calibration(rec)
    except Exception:  # bad readings are named by the checks that follow
        return None


def _write_track_bvh(path, angles, quats, sensors, cal, chains, rate_hz, shape, inputs) -> None:
    """The BVH file of ``track --bvh-out``: the hand's joint angles, attitude and wrist, on the
    skeleton of `shape`, or (None) the standard hand's with the bones the link model measures."""
    import numpy as np

    from ..models import JOINT_NAMES, write_bvh
    from ..sensors.imu import bone_lengths_mm, hand_attitude

    unknown = [n for n, bad in zip(JOINT_NAMES, np.isnan(angles).any(axis=0)) if bad]
    if unknown:  # the thumb's CMC of a calibration without its two rotations
        click.echo(f"handsynth: warning: --bvh-out: {', '.join(unknown)} not measured by this "
                   "calibration, written as 0", err=True)
    wrist_mm = 1e3 * chains["index_joints"][:, 0]
    bones = bone_lengths_mm(chains) if shape is None else None
    write_bvh(path, np.nan_to_num(angles), rate_hz=rate_hz, shape=shape, side=cal.side,
              root_quat=hand_attitude(quats, sensors, cal.frames), root_position_mm=wrist_mm,
              bone_lengths_mm=bones, inputs=inputs)


@imu.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@click.option("--filter", "filter_name", type=click.Choice(_TRACK_FILTERS + _CHAIN_FILTERS),
              default=None, help="Orientation filter [default: vqf; with --calibration filter4, "
                                 "or filter4b: Filter 4 learning drifting gyro biases].")
@click.option("--calibration", "calibration_path", type=click.Path(dir_okay=False),
              help="Calibration JSON from 'handsynth imu calibrate': run Filter 4 and "
                   "write joint angles too.")
@_unit_options
@click.option("--static", "static_s", type=float, default=2.0, show_default=True,
              help="Length of the still start, s (gyro bias, initial attitude).")
@click.option("--align", default=None, metavar="START,END",
              help="Common rotation for the compass azimuth alignment, s (e.g. 2,4); "
                   "6-axis sensors (no magnetometer columns) take their headings from it.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False), required=True,
              help="CSV of quaternions (time_s, <sensor>_qw .. _qz).")
@click.option("--angles-out", type=click.Path(dir_okay=False),
              help="CSV of joint angles in degrees (needs --calibration).")
@click.option("--tips-out", type=click.Path(dir_okay=False),
              help="CSV of fingertip positions from the elbow centre, mm, in the world frame "
                   "of the initial attitude (eq. 3.12; needs --calibration).")
@click.option("--bvh-out", type=click.Path(dir_okay=False),
              help="BVH motion file: the handsynth hand posed by the joint angles, its bones "
                   "as long as the calibration's link model measures them, turned as the hand "
                   "sensor's attitude says and placed at the wrist's place from the elbow "
                   "centre, in the world frame of the initial attitude (needs --calibration).")
@click.option("--bvh-shape", default=None, metavar="NAME",
              help="With --bvh-out, the handsynth hand whose skeleton, bones included, the "
                   "file carries instead (e.g. L1.050_W0.900_P1.000_T1.000, standard) "
                   "[default: the standard hand's directions, the bones measured].")
@click.option("--undo-misplaced", is_flag=True,
              help="Read sensors that read as exchanged or turned on their segments since the "
                   "calibration as put back, one at a time, with a warning naming each "
                   "(needs --calibration); without it they are warned of and read as they are.")
@click.option("--realign-late", is_flag=True,
              help="Read sensors whose streams read late or early against their neighbours "
                   "(a wireless logger's latency) as realigned by the lag found, with a warning "
                   "naming each (needs --calibration); the hand's two sensors against each "
                   "other are not told apart and stay warned of.")
@_no_sensor_calibration
def track(recording, filter_name, calibration_path, acc_units, gyr_units, mag_units, rate_hz,
          acc_range_g, gyr_range_dps, bridge_lost, bridge_max_s, gyr_axes, mag_axes, static_s,
          align, out_path, angles_out, tips_out, bvh_out, bvh_shape, undo_misplaced,
          realign_late, no_sensor_calibration) -> None:
    """Orientation of every sensor of a CSV RECORDING (columns <sensor>_acc_x .. _mag_z)."""
    import numpy as np

    from ..errors import InvalidInputError, RecordingError
    from ..models import JOINT_NAMES
    from ..sensors.imu import (
        FILTER4B,
        ImuCalibration,
        check_recording,
        make_filter,
        sample_times,
    )

    for flag, given in (("--angles-out", angles_out), ("--tips-out", tips_out),
                        ("--bvh-out", bvh_out), ("--undo-misplaced", undo_misplaced),
                        ("--realign-late", realign_late),
                        ("--no-sensor-calibration", no_sensor_calibration),
                        (f"--filter {filter_name}", filter_name in _CHAIN_FILTERS)):
        if given and not calibration_path:
            raise InvalidInputError(f"{flag} needs --calibration")
    if calibration_path and filter_name not in (None, *_CHAIN_FILTERS):
        raise InvalidInputError(f"with --calibration the filter is one of {', '.join(_CHAIN_FILTERS)}, "
                                f"got {filter_name}")
    inputs = (recording, calibration_path)
    if bvh_shape is not None and not bvh_out:
        raise InvalidInputError("--bvh-shape says whose skeleton --bvh-out carries, and "
                                "--bvh-out was not given")
    check_outputs([("--out", out_path), ("--angles-out", angles_out), ("--tips-out", tips_out),
                   ("--bvh-out", bvh_out)], inputs=inputs)
    skeleton = shape_option(bvh_shape, "--bvh-shape") if bvh_shape is not None else None
    static = _static_start(static_s, align)
    full_scale = _full_scale(acc_range_g, gyr_range_dps)
    rec = _read(recording, acc_units=acc_units, gyr_units=gyr_units, mag_units=mag_units,
                rate_hz=rate_hz, bridge_lost=bridge_lost, bridge_max_s=bridge_max_s,
                gyr_axes=gyr_axes, mag_axes=mag_axes)
    if static_s * rec.rate_hz > rec.n + 0.5:  # as check_static_fits, in the option's words
        raise RecordingError(f"{recording}: the static start --static {static_s:g} s is longer than "
                             f"the recording ({rec.n} samples, {rec.duration_s:.3g} s); shorten "
                             "--static")
    cal = ImuCalibration.load(calibration_path) if calibration_path else None
    if cal is not None:
        try:
            cal.correct(rec, sensor_calibration=False)  # its sensors, before any work
        except RecordingError as exc:
            raise RecordingError(f"{recording} (calibration {calibration_path}): {exc}") from None
    # the magnetometers' field strength judged as the calibration corrects them
    corrects = None if cal is None or no_sensor_calibration else cal.sensor_calibration
    for w in check_recording(rec, static_s=static_s, source=str(recording),
                             sensor_calibration=corrects, **full_scale):
        click.echo(f"handsynth: warning: {w}", err=True)
    t = sample_times(rec)  # the recording's own times
    if cal is not None:
        name = filter_name or "filter4"
        res = cal.track(rec, static=static, sensor_calibration=not no_sensor_calibration,
                        options=FILTER4B if name == "filter4b" else None,
                        undo_misplaced=undo_misplaced, realign_late=realign_late)
        q, sensors = res["quat"], cal.sensors
        if res["sensor_calibration"]:
            name += ", sensor calibration applied"
        if cal.plate is not None:
            name += ", forearm plate fused"
        if angles_out:
            _write_table(angles_out, ["time_s", *JOINT_NAMES], np.column_stack([t, res["angles"]]),
                         inputs=inputs)
        if tips_out:
            tips = res["tips"]
            _write_table(tips_out, ["time_s", *_tip_columns(tips)],
                         np.column_stack([t, *(1e3 * v for v in tips.values())]), inputs=inputs)
        if bvh_out:
            _write_track_bvh(bvh_out, res["angles"], q, sensors, cal, res["chains"], rec.rate_hz,
                             skeleton, inputs)
    else:
        name = filter_name or "vqf"
        est = dataclasses.replace(make_filter(name), static=static)
        q, sensors = est.run(rec), rec.sensors
    cols = ["time_s"] + [f"{s}_q{c}" for s in sensors for c in "wxyz"]
    _write_table(out_path, cols, np.column_stack([t] + [q[k, :, c] for k in range(q.shape[0])
                                                         for c in range(4)]), inputs=inputs)
    if not rec.has_mag:
        name += ", 6-axis: headings from the common rotation"
    click.echo(f"{len(sensors)} sensors, {rec.n} samples ({rec.duration_s:.1f} s) at "
               f"{rec.rate_hz:g} Hz -> {out_path} ({name})")


def _tip_columns(fingers) -> list[str]:
    """The columns of fingertip positions, mm: ``<finger>_tip_x_mm`` .."""
    return [f"{f}_tip_{c}_mm" for f in fingers for c in "xyz"]


def _static_start(static_s, align):
    """``--static`` and ``--align START,END`` as a :class:`StaticStart`."""
    from ..errors import InvalidInputError
    from ..sensors.imu import StaticStart

    a = b = None
    if align:
        try:
            a, b = (float(x) for x in align.split(","))
        except ValueError:
            raise InvalidInputError(f"--align must be START,END in seconds, got {align!r}") from None
    return StaticStart(static_s=static_s, align_start_s=a, align_end_s=b)


@imu.command()
@click.option("--calibration", "calibration_path", type=click.Path(dir_okay=False), required=True,
              help="Calibration JSON from 'handsynth imu calibrate'.")
@click.option("--rate", "rate_hz", type=float, required=True,
              help="The sensors' sampling rate, Hz (the lines are taken to come at it; where "
                   "a time column skips samples, they were lost).")
@click.option("--acc-units", type=click.Choice(("m/s2", "g", "mg")), default="m/s2",
              show_default=True)
@click.option("--gyr-units", type=click.Choice(("rad/s", "deg/s")), default="rad/s",
              show_default=True)
@click.option("--mag-units", type=click.Choice(("uT", "mT", "G", "nT")), default="uT",
              show_default=True)
@click.option("--static", "static_s", type=float, default=2.0, show_default=True,
              help="Length of the still start, s: no line is answered before it is read.")
@click.option("--align", default=None, metavar="START,END",
              help="Common rotation for the compass azimuth alignment, s (answers start "
                   "after END).")
@click.option("--filter", "filter_name", type=click.Choice(_CHAIN_FILTERS), default="filter4",
              show_default=True, help="Filter 4, or filter4b (learning drifting gyro biases).")
@click.option("--input", "source", type=click.File("r"), default="-", show_default=True,
              help="CSV lines to read (- : standard input).")
@click.option("--out", "out", type=click.File("w"), default="-", show_default=True,
              help="Joint angles CSV to write as they come (- : standard output).")
@click.option("--max-hold", "max_hold_s", type=float, default=None, metavar="SECONDS",
              help="Longest loss of one sensor's readings filled in (predicted from the "
                   "other sensors') before the stream stops, s [default: 0.5].")
@click.option("--tips", is_flag=True,
              help="Also write the fingertips from the elbow centre, mm (as track's "
                   "--tips-out), after the joint angles.")
@click.option("--check-every", "check_s", type=float, default=20.0, show_default=True,
              metavar="SECONDS",
              help="Check each stretch of this many seconds as track checks a recording "
                   "(sensors exchanged, streams out of step, joints beyond range), warning "
                   "once of each finding; 0: never.")
@_no_sensor_calibration
def stream(calibration_path, rate_hz, acc_units, gyr_units, mag_units, static_s, align,
           filter_name, source, out, max_hold_s, tips, check_s, no_sensor_calibration) -> None:
    """Joint angles of live CSV lines (a logger's output piped in), one line out per sample.

    The input is 'imu track's CSV one line at a time (a header first); each sample's joint
    angles (time_s, the 20 joints in degrees, and held_sensors: how many sensors' readings
    were lost there and filled in) are written and flushed as soon as the next sample has
    come. A reading lost (an empty or non-finite cell, or a line a time column says was
    dropped) is filled in for up to --max-hold. Each stretch of --check-every seconds is
    checked as 'imu track' checks a recording, and what is found is warned of on standard
    error once.
    """
    import numpy as np

    from ..models import JOINT_NAMES
    from ..sensors.imu import CHAINS, FILTER4B, ImuCalibration, stream_csv

    cal = ImuCalibration.load(calibration_path)
    out.write(",".join(["time_s", *JOINT_NAMES, *(_tip_columns(CHAINS) if tips else ()),
                        "held_sensors"]) + "\n")
    out.flush()
    rows = 0
    for done in stream_csv(source, cal, rate_hz=rate_hz, acc_units=acc_units,
                           gyr_units=gyr_units, mag_units=mag_units,
                           source=input_name(source),
                           static=_static_start(static_s, align),
                           options=FILTER4B if filter_name == "filter4b" else None,
                           sensor_calibration=not no_sensor_calibration,
                           check_s=check_s or None,
                           **({} if max_hold_s is None else {"max_hold_s": max_hold_s})):
        where = (np.column_stack([1e3 * done.tips_m[f] for f in CHAINS]) if tips and len(done)
                 else np.empty((len(done), 0)))
        for t, row, at, held in zip(done.t_s, done.angles_deg, where, done.held.sum(axis=0)):
            out.write(f"{t:.6f}," + ",".join(f"{v:.4f}" for v in (*row, *at)) + f",{held}\n")
        rows += len(done)
        if len(done):
            out.flush()
    click.echo(f"{rows} samples tracked ({filter_name})", err=True)


@imu.command()
@click.argument("directory", type=click.Path(file_okay=False))
@click.option("--filter", "filters", multiple=True,
              help="Filter(s), comma-separated or repeated (default: all single-IMU filters).")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write per-trial errors as JSON.")
def broad(directory, filters, json_out) -> None:
    """Run the filters on the BROAD trials present in DIRECTORY (the dataset's metric)."""
    from ..sensors.imu import BROAD_FILTERS, find_broad_trials, run_broad

    trials = find_broad_trials(directory)
    check_outputs([("--json", json_out)], inputs=trials)
    res = run_broad(directory, filters=_filters(filters, BROAD_FILTERS),
                    progress=lambda line: click.echo(line, err=True))
    if json_out:
        write_json(json_out, res, inputs=trials)
    click.echo(f"{len(res['trials'])} BROAD trial(s); mean RMSE over the movement phases, deg "
               f"({res['anchor']})")
    click.echo(f"{'filter':<10}{'total':>8}{'heading':>9}{'inclination':>13}")
    for name, m in res["mean"].items():
        click.echo(f"{name:<10}{m['total_rmse_deg']:8.2f}{m['heading_rmse_deg']:9.2f}"
                   f"{m['inclination_rmse_deg']:13.2f}")
