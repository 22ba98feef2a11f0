"""``handsynth joints``: finger joint centres from two 6-DOF sensors."""

from __future__ import annotations

import json
from pathlib import Path

import click

from ._main import cli

_METHODS = ("patent", "variance3d", "obrien", "score")
#: Bounds of ``joints eval``: a trial holds still for its first 0.5 s; 3600 s at 240 Hz
#: is 864,000 frames per trial and estimator.
_MIN_DURATION_S, _MAX_DURATION_S = 2.0, 3600.0
_MAX_SEEDS = 100


def _write_json(path: str, payload, inputs=()) -> None:
    from .._io import write_text

    write_text(path, json.dumps(payload, indent=2) + "\n", what="JSON file", inputs=inputs)


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
                   "auto, recording, x, y, z or 'ax,ay,az' (transmitter frame).")
@click.option("--bins", type=int, default=100, show_default=True,
              help="Bins of the axis-angle filter.")
@click.option("--units", type=click.Choice(("cm", "in", "mm", "m")), default="cm",
              show_default=True, help="Position unit of a text export.")
@click.option("--angles", type=click.Choice(("euler", "quaternion")), default="euler",
              show_default=True, help="Orientation columns of a text export.")
@click.option("--rate", "rate_hz", type=float, default=240.0, show_default=True,
              help="Sampling rate of a text export without times, Hz.")
@click.option("--drop-invalid", is_flag=True,
              help="Drop frames with NaN or missing rows instead of failing.")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write the results as JSON.")
@click.option("--plot", "plot_out", type=click.Path(dir_okay=False),
              help="Write the axis-angle histogram (PNG).")
def estimate(recording, methods, frames, lateral_axis, bins, units, angles, rate_hz,
             drop_invalid, json_out, plot_out) -> None:
    """Estimate the joint centre of RECORDING (.h5 or Polhemus text export)."""
    from .._io import check_output
    from ..sensors.trackers import (
        AxisAngleFilter,
        make_estimator,
        plot_axis_histogram,
        read_recording,
    )

    for path in (json_out, plot_out):  # before the work: a bad name fails now
        if path:
            check_output(path, inputs=[recording])
    kwargs = {}
    if Path(recording).suffix.lower() not in (".h5", ".hdf5"):
        kwargs = dict(units=units, angles=angles, rate_hz=rate_hz,
                      on_invalid="drop" if drop_invalid else "raise")
    rec = read_recording(recording, **kwargs)
    filt = AxisAngleFilter(bins=bins, lateral_axis=_lateral(lateral_axis))
    names = _METHODS if "all" in methods else tuple(dict.fromkeys(methods))
    modes = ("all", "filtered") if frames == "both" else (frames,)
    results = [make_estimator(m, frames=mode, axis_filter=filt).estimate(rec)
               for m in names for mode in modes]

    head = (f"{'method':<11}{'frames':<9}{'used':>6}  {'P_U (mm, upper sensor)':<26}"
            f"{'P_L (mm, lower sensor)':<26}{'|PU-PL|':>8}{'resid':>7}")
    if rec.truth is not None:
        head += f"{'err_U':>7}{'err_L':>7}"
    click.echo(f"{rec.joint}: {rec.n_frames} frames, {rec.duration_s:.1f} s, "
               f"sensors {rec.labels[0]} / {rec.labels[1]}")
    click.echo(head)
    rows = []
    for r in results:
        pu = " ".join(f"{v:7.2f}" for v in r.centre_upper * 1e3)
        pl = " ".join(f"{v:7.2f}" for v in r.centre_lower * 1e3)
        line = (f"{r.method:<11}{r.frames_mode:<9}{r.frames.size:>6}  {pu:<26}{pl:<26}"
                f"{r.distance_mm:8.2f}{r.residual_mm:7.2f}")
        row = r.to_dict()
        if rec.truth is not None:
            err = r.error_mm(rec)
            line += f"{err[0]:7.2f}{err[1]:7.2f}"
            row["error_mm"] = [round(float(e), 4) for e in err]
        click.echo(line)
        rows.append(row)
    if json_out:
        _write_json(json_out, {"recording": str(recording), "joint": rec.joint,
                               "n_frames": rec.n_frames, "results": rows}, inputs=[recording])
    if plot_out:
        filtered = next((r.axis_filter for r in results if r.axis_filter is not None), None)
        plot_axis_histogram(filtered if filtered is not None else filt.apply(rec), plot_out,
                            title=f"{rec.joint}: axis-angle filter", inputs=[recording])


@joints.command("eval")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write the table as JSON.")
@click.option("--duration", "duration_s", type=float, default=30.0, show_default=True,
              help="Simulated trial length, s.")
@click.option("--rate", "rate_hz", type=click.Choice(("240", "120")), default="240",
              show_default=True, help="Sampling rate, Hz.")
@click.option("--seeds", type=int, default=3, show_default=True,
              help="Number of simulated trials per row (averaged).")
def eval_(json_out, duration_s, rate_hz, seeds) -> None:
    """Reproduce the patent's table (mock vs finger, all vs filtered) on simulated data."""
    from .._io import check_output
    from ..errors import InvalidInputError
    from ..sensors.trackers import evaluate

    if not 1 <= seeds <= _MAX_SEEDS:
        raise InvalidInputError(f"--seeds must be between 1 and {_MAX_SEEDS}, got {seeds}")
    if not _MIN_DURATION_S <= duration_s <= _MAX_DURATION_S:
        raise InvalidInputError(
            f"--duration must be between {_MIN_DURATION_S:g} and {_MAX_DURATION_S:g} s (a trial "
            f"starts with a still {_MIN_DURATION_S / 4:g} s), got {duration_s:g}")
    if json_out:
        check_output(json_out)
    rows = evaluate(duration_s=duration_s, rate_hz=float(rate_hz), seeds=tuple(range(seeds)))
    click.echo("errors in mm against the simulated centre; |PU-PL| as in the patent "
               "(mock ~2 mm; finger DIP 7.09 -> 4.21 mm)")
    click.echo(f"{'scenario':<9}{'noise':<20}{'method':<11}{'frames':<9}{'used':>6}"
               f"{'err_U':>8}{'err_L':>8}{'|PU-PL|':>9}{'ms':>7}")
    for r in rows:
        click.echo(f"{r['scenario']:<9}{r['noise']:<20}{r['method']:<11}{r['frames']:<9}"
                   f"{r['n_frames_used']:>6}{r['error_upper_mm']:8.2f}{r['error_lower_mm']:8.2f}"
                   f"{r['distance_mm']:9.2f}{r['time_ms']:7.1f}")
    if json_out:
        _write_json(json_out, {"duration_s": duration_s, "rate_hz": float(rate_hz),
                               "seeds": seeds, "rows": rows})
