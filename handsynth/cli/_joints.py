"""``handsynth joints``: finger joint centres from two 6-DOF sensors."""

from __future__ import annotations

import warnings
from pathlib import Path

import click

from ._main import cli

_METHODS = ("patent", "variance3d", "obrien", "score")
#: Bounds of ``joints eval``: a trial holds still for its first 0.5 s; 3600 s at 240 Hz
#: is 864,000 frames per trial and estimator.
_MIN_DURATION_S, _MAX_DURATION_S = 2.0, 3600.0
_MAX_SEEDS = 100


def _lateral(value: str):
    if value in ("auto", "recording"):
        return value
    axes = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}
    if value in axes:
        return axes[value]
    try:
        vec = tuple(float(v) for v in value.split(","))
    except ValueError:
        vec = ()
    if len(vec) != 3:
        raise click.BadParameter(
            f"expected auto, recording, x, y, z or 'ax,ay,az', got {value!r}",
            param_hint="--lateral-axis",
        )
    return vec


def _check_rate(recording: str, rec, rate_hz: float) -> None:
    """Warn when a --rate given on the command line differs by more than 1 % from the rate
    of the export's time column, which is what the reader uses."""
    ctx = click.get_current_context()
    if ctx.get_parameter_source("rate_hz") is click.core.ParameterSource.DEFAULT:
        return
    if rec.metadata.get("times_from") != "time column":
        return
    if abs(rate_hz - rec.rate_hz) > 0.01 * rec.rate_hz:
        warnings.warn(
            f"--rate {rate_hz:g} Hz is not used: {recording} has a time column, whose times "
            f"give {rec.rate_hz:.4g} Hz; the time column is what is used", stacklevel=2)


@cli.group()
def joints() -> None:
    """Finger joint centres from two 6-DOF trackers (patent JP2010-88628)."""


@joints.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@click.option("--method", "methods", type=click.Choice(_METHODS + ("all",)),
              multiple=True, default=("all",), show_default=True,
              help="Estimator(s); repeat the option for several.")
@click.option("--frames", type=click.Choice(("all", "filtered", "both")), default="both",
              show_default=True, help="All frames, axis-angle-filtered frames, or both.")
@click.option("--lateral-axis", default="auto", show_default=True,
              help="Finger width direction for the filter and the patent's plane: "
                   "auto, recording, x, y, z or 'ax,ay,az'.")
@click.option("--lateral-frame", type=click.Choice(("transmitter", "upper")),
              default="transmitter", show_default=True,
              help="Frame of a --lateral-axis vector: the transmitter's at the standard state, "
                   "or the upper sensor's own (fixed to the finger).")
@click.option("--bins", type=int, default=100, show_default=True,
              help="Bins of the axis-angle filter.")
@click.option("--units", type=click.Choice(("auto", "cm", "in", "mm", "m")), default="auto",
              show_default=True, help="Position unit of a text export (auto: judged by the "
                                      "sensor spacing).")
@click.option("--angles", type=click.Choice(("auto", "euler", "quaternion")), default="auto",
              show_default=True, help="Orientation columns of a text export (auto: detected).")
@click.option("--sensors", default=None,
              help="Station numbers of the upper and lower sensor, e.g. '1,2' (default: the "
                   "two in the file).")
@click.option("--rate", "rate_hz", type=float, default=240.0, show_default=True,
              help="Sampling rate of a text export without times, Hz (a time column is "
                   "used instead; a --rate that differs from it is warned about).")
@click.option("--strict", is_flag=True,
              help="Refuse a file with lost lines, NaN frames or glitches instead of dropping "
                   "those frames.")
@click.option("--take", type=int, default=1, show_default=True,
              help="Which take of a text export whose time or frame counter restarts (takes "
                   "written into one file): 1 the first.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write the report and results as JSON.")
@click.option("--plot", "plot_out", type=click.Path(dir_okay=False),
              help="Write the axis-angle histogram (PNG).")
def estimate(recording, methods, frames, lateral_axis, lateral_frame, bins, units, angles,
             sensors, rate_hz, strict, take, json_out, plot_out) -> None:
    """Estimate the joint centre of RECORDING (.h5, PiMgr CSV or Liberty ASCII)."""
    from .._io import check_outputs, write_json
    from ..errors import EstimationError, InvalidInputError
    from ..sensors.trackers import (
        AxisAngleFilter,
        estimate_all,
        motion_quality,
        plot_axis_histogram,
        read_recording,
    )

    # before the work: a bad name fails now
    check_outputs([("--json", json_out), ("--plot", plot_out)], inputs=[recording])
    kwargs = {}
    if Path(recording).suffix.lower() in (".h5", ".hdf5"):
        ctx = click.get_current_context()
        given = [f"--{name.replace('_hz', '')}" for name in ("units", "angles", "sensors", "rate_hz",
                                                              "take")
                 if ctx.get_parameter_source(name) is not click.core.ParameterSource.DEFAULT]
        if given:
            raise InvalidInputError(
                f"{', '.join(given)} apply to text exports (PiMgr CSV, Liberty ASCII), not to "
                f"the HDF5 recording {recording!r}, which stores units, rotations and sensors")
    else:
        from .._checks import check_number

        check_number(rate_hz, "--rate", above=0.0, maximum=100_000.0)
        kwargs = dict(units=units, angles=None if angles == "auto" else angles,
                      rate_hz=rate_hz, on_invalid="raise" if strict else "drop", take=take)
        if sensors is not None:
            try:
                st = tuple(int(v) for v in sensors.split(","))
            except ValueError:
                st = ()
            if len(st) != 2:
                raise InvalidInputError(f"--sensors: expected two station numbers 'a,b', got "
                                        f"{sensors!r}")
            kwargs["sensors"] = st
    rec = read_recording(recording, **kwargs)
    if kwargs:
        _check_rate(recording, rec, rate_hz)
    filt = AxisAngleFilter(bins=bins, lateral_axis=_lateral(lateral_axis),
                           lateral_frame=lateral_frame)
    names = _METHODS if "all" in methods else tuple(dict.fromkeys(methods))
    modes = ("all", "filtered") if frames == "both" else (frames,)

    quality = motion_quality(rec)
    click.echo(f"{rec.joint}: sensors {rec.labels[0]} / {rec.labels[1]}")
    for line in quality.lines():
        click.echo(line)
    results, refused = estimate_all(rec, names, frames_modes=modes, axis_filter=filt)

    head = (f"{'method':<11}{'frames':<9}{'used':>6}  {'P_U (mm, upper sensor)':<26}"
            f"{'P_L (mm, lower sensor)':<26}{'|PU-PL|':>8}{'resid':>7}{'exp.err':>8}")
    if rec.truth is not None:
        head += f"{'err_U':>7}{'err_L':>7}"
    click.echo(head)
    rows = []
    for r in results:
        pu = " ".join(f"{v:7.2f}" for v in r.centre_upper * 1e3)
        pl = " ".join(f"{v:7.2f}" for v in r.centre_lower * 1e3)
        exp = r.determinability.expected_error_mm[1] if r.determinability is not None else float("nan")
        line = (f"{r.method:<11}{r.frames_mode:<9}{r.frames.size:>6}  {pu:<26}{pl:<26}"
                f"{r.distance_mm:8.2f}{r.residual_mm:7.2f}{exp:8.2f}")
        row = r.to_dict()
        if rec.truth is not None:
            err = r.error_mm(rec)
            line += f"{err[0]:7.2f}{err[1]:7.2f}"
            row["error_mm"] = [round(float(e), 4) for e in err]
        if r.determined == "axis":
            line += "  axis only"
        click.echo(line)
        rows.append(row)
    for r in results:
        for w in r.warnings:
            click.echo(f"  {r.method}/{r.frames_mode}: warning: {w}")
    for x in refused:
        click.echo(f"  {x['method']}/{x['frames_mode']}: refused: {x['refused']}")
    if json_out:
        write_json(json_out, {"recording": str(recording), "joint": rec.joint,
                              "n_frames": rec.n_frames, "quality": quality.to_dict(),
                              "results": rows, "refused": refused}, inputs=[recording])
    if plot_out and results:
        filtered = next((r.axis_filter for r in results if r.axis_filter is not None), None)
        plot_axis_histogram(filtered if filtered is not None else filt.apply(rec), plot_out,
                            title=f"{rec.joint}: axis-angle filter", inputs=[recording])
    if not results:
        raise EstimationError(f"no method gave a centre: {refused[0]['refused']}")


@joints.command("eval")
@click.option("--config", "configs", type=click.Choice(("project", "independent", "both")),
              default="both", show_default=True,
              help="Simulator configuration: the project's own, a second one that differs in "
                   "joint, placement, kinematics and error model, or both.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write the table as JSON.")
@click.option("--duration", "duration_s", type=float, default=30.0, show_default=True,
              help="Simulated trial length, s.")
@click.option("--seeds", type=int, default=3, show_default=True,
              help="Number of simulated trials per row (averaged).")
@click.option("--seed", "first_seed", type=int, default=0, show_default=True,
              help="Seed of the first trial; the others follow it (--seeds 3 --seed 10: "
                   "10, 11, 12).")
@click.option("--rom-sweep", is_flag=True,
              help="Instead: every method at 10-70 deg range of motion, ok / warned / refused.")
def eval_(configs, json_out, duration_s, seeds, first_seed, rom_sweep) -> None:
    """The patent's table (mock vs finger, all vs filtered) on two simulator configurations."""
    from .._io import check_output, write_json
    from ..errors import InvalidInputError
    from ..sensors.trackers import evaluate
    from ..sensors.trackers import rom_sweep as sweep

    if not 1 <= seeds <= _MAX_SEEDS:
        raise InvalidInputError(f"--seeds must be between 1 and {_MAX_SEEDS}, got {seeds}")
    if first_seed < 0:
        raise InvalidInputError(f"--seed must be a seed >= 0, got {first_seed}")
    trial_seeds = tuple(range(first_seed, first_seed + seeds))
    if not _MIN_DURATION_S <= duration_s <= _MAX_DURATION_S:
        raise InvalidInputError(
            f"--duration must be between {_MIN_DURATION_S:g} and {_MAX_DURATION_S:g} s (a trial "
            f"starts with a still {_MIN_DURATION_S / 4:g} s), got {duration_s:g}")
    if json_out:
        check_output(json_out)
    names = ("project", "independent") if configs == "both" else (configs,)
    if rom_sweep:
        rows = sweep(configs=names, duration_s=min(duration_s, 20.0), seeds=trial_seeds)
        click.echo("largest of the P_U/P_L errors in mm; W = answered with a warning, "
                   "R = refused; baseline = midpoint of the two sensors")
        click.echo(f"{'config':<12}{'scenario':<9}{'rom':>4} {'method':<11}{'frames':<9}"
                   f"{'status':<8}{'error':>8}{'baseline':>9}")
        for r in rows:
            click.echo(f"{r['config']:<12}{r['scenario']:<9}{r['rom_deg']:>4} {r['method']:<11}"
                       f"{r['frames']:<9}{r['status']:<8}{r['error_mm']:8.2f}"
                       f"{r['baseline_mm']:9.2f}")
        if json_out:
            write_json(json_out, {"duration_s": min(duration_s, 20.0), "seeds": seeds,
                                  "first_seed": first_seed, "rows": rows})
        return
    rows = [r for c in names for r in evaluate(config=c, duration_s=duration_s,
                                               seeds=trial_seeds)]
    click.echo("errors in mm against the simulated centre (mean over answered trials; worst = the "
               "largest trial's mean of U and L); axis = "
               "distance of the true centre from the estimated axis; |PU-PL| as in the patent "
               "(mock ~2 mm; finger DIP 7.09 -> 4.21 mm); midpoint = the trivial baseline")
    click.echo(f"{'config':<12}{'scenario':<9}{'noise':<20}{'method':<11}{'frames':<9}"
               f"{'used':>6}{'err_U':>8}{'err_L':>8}{'worst':>7}{'axis':>7}{'|PU-PL|':>9}"
               f"{'ans/warn/ref':>14}"
               f"{'ms':>7}")
    for r in rows:
        counts = f"{r['answered']}/{r['warned']}/{r['refused']}"
        click.echo(f"{r['config']:<12}{r['scenario']:<9}{r['noise']:<20}{r['method']:<11}"
                   f"{r['frames']:<9}{r['n_frames_used']:>6}{r['error_upper_mm']:8.2f}"
                   f"{r['error_lower_mm']:8.2f}{r['worst_error_mm']:7.2f}{r['axis_error_mm']:7.2f}"
                   f"{r['distance_mm']:9.2f}"
                   f"{counts:>14}"
                   f"{r['time_ms']:7.1f}")
    if json_out:
        # a row whose every trial was refused has NaN errors: written as null
        write_json(json_out, {"duration_s": duration_s, "seeds": seeds,
                              "first_seed": first_seed, "rows": rows})
