"""``handsynth glove``: all joint angles from a five-sensor data glove (seed 004)."""

from __future__ import annotations

import click

from ._main import cli, input_name

_MODELS = ("model1", "model2", "model3", "model4")


@cli.group()
def glove() -> None:
    """All 20 joint angles from a five-sensor data glove (seed 004)."""


@glove.command()
@click.argument("out", type=click.Path(dir_okay=False))
@click.option("--kind", type=click.Choice(("dg5", "5dt")), default="dg5", show_default=True,
              help="Glove design: sensors over the PIP (dg5) or over MCP and PIP (5dt).")
@click.option("--user", "user_seed", type=int, default=0, show_default=True,
              help="Seed of the simulated wearer (hand, rest posture, grasp style).")
@click.option("--donning", type=int, default=0, show_default=True,
              help="Seed of this wearing of the glove (offsets, gains, slip).")
@click.option("--motion", "motions", multiple=True,
              help="Motion to record (repeat); default the glove's representative motions.")
@click.option("--trials", type=click.IntRange(1, 100), default=5, show_default=True,
              help="Trials per motion.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of trial variation and noise.")
@click.option("--range-holds/--no-range-holds", default=True, show_default=True,
              help="Add open-hand and fist holds (motions 'range_open', 'range_fist') for "
                   "the range calibration.")
@click.option("--no-angles", is_flag=True, help="Leave out the reference joint angles.")
@click.option("--adc-max", type=int, default=4095, show_default=True,
              help="Clip the simulated readings to 0..adc-max counts, to try saturation "
                   "(the sensors keep a 12-bit converter's offsets and gains; 4095: none "
                   "clipped).")
def simulate(out, kind, user_seed, donning, motions, trials, seed, range_holds, no_angles,
             adc_max):
    """Write a simulated glove recording OUT (CSV, canonical joint names)."""
    from dataclasses import replace

    from .._checks import check_integer
    from .._io import check_output
    from ..errors import InvalidInputError
    from ..sensors.glove import (
        MOTIONS,
        GloveRecording,
        don_glove,
        make_user,
        motions_for,
        simulate_range_holds,
        simulate_session,
        write_glove_csv,
    )

    check_output(out, what="glove CSV")  # before the simulation, not after it
    for flag, value in (("--user", user_seed), ("--donning", donning), ("--seed", seed)):
        if value < 0:
            raise InvalidInputError(f"{flag} must be a seed >= 0, got {value}")
    check_integer(adc_max, "--adc-max", minimum=1)
    for i, m in enumerate(motions):
        if m not in MOTIONS:
            raise InvalidInputError(f"--motion: unknown motion {m!r}; expected one of "
                                    f"{', '.join(MOTIONS)}")
        if m in motions[:i]:
            raise InvalidInputError(f"--motion {m} is given twice; for more trials of it use "
                                    "--trials")
    user = make_user(user_seed)
    params = replace(don_glove(user, kind, seed=donning), adc_max=adc_max)
    rec = simulate_session(user, params, motions or motions_for(kind), trials=trials, seed=seed)
    if range_holds:
        holds = simulate_range_holds(user, params, seed=seed + 1, start_s=rec.time_s[-1] + 1.0)
        rec = GloveRecording.concatenate([rec, holds])
    write_glove_csv(out, rec, with_angles=not no_angles)
    click.echo(f"wrote {rec.n_samples} samples ({kind}, {user.name}) to {out}")


@glove.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@click.option("-o", "--out", "out", type=click.Path(dir_okay=False), required=True,
              help="Calibration file to write (JSON).")
@click.option("--kind", type=click.Choice(("dg5", "5dt")), required=True,
              help="Glove design (fixes which joints the sensors span).")
@click.option("--model", "models", type=click.Choice(_MODELS), multiple=True,
              help="Model(s) to fit (repeat); default all four.")
@click.option("--t-threshold", type=float, default=2.0, show_default=True,
              help="|t| below which models 3 and 4 drop a sensor (seed eq. 11).")
@click.option("--points", "n_points", type=int, default=20, show_default=True,
              help="Points along each motion for the mixing likelihood (seed eq. 4), 1-200.")
@click.option("--synergies", "synergy_k", type=int, default=2, show_default=True,
              help="Synergies of the synergy baseline (0 leaves it out).")
@click.option("--synergy-csv", type=click.Path(dir_okay=False),
              help="Learn the synergies from this 22-sensor CyberGlove-style export instead of "
                   "the hand model's natural pose set.")
@click.option("--synergy-units", type=click.Choice(("deg", "rad")), default="deg",
              show_default=True, help="Angle unit of --synergy-csv.")
@click.option("--adc-max", type=float, default=4095.0, show_default=True,
              help="Full scale of the readings, counts.")
def calibrate(recording, out, kind, models, t_threshold, n_points, synergy_k, synergy_csv,
              synergy_units, adc_max):
    """Fit every estimator on RECORDING (CSV with motions and reference angles)."""
    from .._checks import check_integer, check_number
    from .._io import check_output
    from ..errors import InvalidInputError
    from ..sensors.glove import (
        CalibrationOptions,
        RegressionEstimator,
        fit_synergies,
        range_readings,
        read_cyberglove_csv,
        read_glove_csv,
        save_calibration,
    )
    from ..sensors.glove import calibrate as fit

    check_output(out, what="calibration file", inputs=[recording, synergy_csv])
    check_number(t_threshold, "--t-threshold", minimum=0)
    check_integer(n_points, "--points", minimum=1, maximum=200)
    check_integer(synergy_k, "--synergies", minimum=0, maximum=20)
    if synergy_csv and synergy_k < 1:
        raise InvalidInputError("--synergy-csv needs --synergies >= 1, got --synergies 0")
    rec = read_glove_csv(recording, kind=kind, adc_max=adc_max)
    opts = CalibrationOptions(models=tuple(models) or _MODELS, t_threshold=t_threshold,
                              n_points=n_points, synergy_k=synergy_k)
    synergies = None
    if synergy_csv:
        synergies = fit_synergies(read_cyberglove_csv(synergy_csv, units=synergy_units),
                                  k=synergy_k, source=str(synergy_csv))
        click.echo(f"synergies from {synergy_csv}: {synergy_k} explain "
                   f"{100 * synergies.explained.sum():.1f} % of the posture variance")
    est = fit(rec, options=opts, synergies=synergies, where=str(recording))
    ref = range_readings(rec, where=str(recording))
    # each estimator carries the range of the readings (checked by its predict)
    save_calibration(out, est, kind=kind, range_reference=ref,
                     meta={"recording": str(recording), "n_samples": rec.n_samples})
    click.echo(f"{recording}: {rec.n_samples} rows read; estimators: {', '.join(est)}")
    click.echo("range holds (open, fist): " + ("stored" if ref is not None else
                                               "none; apply cannot take --range"))
    best = next((est[m] for m in ("model4", "model3", "model2", "model1") if m in est), None)
    if isinstance(best, RegressionEstimator):
        click.echo(f"R^2 of the joint-3 (MCP) fits of {best.name} (seed Table 6):")
        from ..sensors.glove import finger_joints

        j3 = [f["j3"] for f in finger_joints()]
        click.echo(f"{'motion':<20}" + "".join(f"{f:>8}" for f in
                                               ("thumb", "index", "middle", "ring", "little")))
        for m, mm in best.models.items():
            click.echo(f"{m:<20}" + "".join(f"{mm.fits[j].r2:8.3f}" for j in j3))
    click.echo(f"wrote {out}")


def _estimator_options(f):
    """``--model``, ``--motion``, ``--range`` and ``--adc-max`` of apply and stream."""
    f = click.option("--adc-max", type=float, default=4095.0, show_default=True,
                     help="Full scale of the readings, counts.")(f)
    f = click.option("--range", "range_csv", type=click.Path(dir_okay=False),
                     help="CSV with open-hand and fist holds of this wearing (motions "
                          "'range_open', 'range_fist'): map the readings onto the "
                          "calibration's first.")(f)
    f = click.option("--motion", default=None,
                     help="The representative motion, when known; default mix over all "
                          "(eqs. 4-6).")(f)
    return click.option("--model", "name", default="model4", show_default=True,
                        help="Estimator in the calibration file: model1..model4, "
                             "pooled_model4, synergy, model4+synergy or constant.")(f)


@glove.command()
@click.argument("calibration", type=click.Path(dir_okay=False))
@click.argument("readings", type=click.Path(dir_okay=False))
@click.option("-o", "--out", "out", type=click.Path(dir_okay=False), required=True,
              help="Joint angles to write (CSV, canonical joint names, degrees).")
@_estimator_options
def apply(calibration, readings, out, name, motion, range_csv, adc_max):
    """Estimate joint angles from READINGS (CSV) with CALIBRATION (JSON)."""
    from ..sensors.glove import apply_calibration

    angles = apply_calibration(calibration, readings, out, model=name, motion=motion,
                               range_csv=range_csv, adc_max=adc_max)
    click.echo(f"{readings}: {len(angles)} samples -> {out} ({name}"
               + (f", motion {motion}" if motion else ", mixed over motions") + ")")


@glove.command()
@click.argument("calibration", type=click.Path(dir_okay=False))
@_estimator_options
@click.option("--input", "source", type=click.File("r"), default="-", show_default=True,
              help="Glove CSV lines to read (- : standard input).")
@click.option("--out", type=click.File("w"), default="-", show_default=True,
              help="Joint angles CSV to write as they come (- : standard output).")
def stream(calibration, name, motion, range_csv, adc_max, source, out):
    """Joint angles of live glove lines (a glove's output piped in), one line out per line.

    The input is 'glove apply's CSV one line at a time (a header first); each line's 20
    joint angles (degrees, after time_s, or the line's sample number from 0 where the input
    has no time column) are written and flushed at once, the same as 'glove apply' writes.
    """
    import math

    from ..models import JOINT_NAMES
    from ..sensors.glove import stream_glove_csv

    rows = 0
    for t, angles in stream_glove_csv(source, calibration, model=name, motion=motion,
                                      range_csv=range_csv, adc_max=adc_max,
                                      source=input_name(source)):
        if rows == 0:
            out.write(",".join(["sample" if t is None else "time_s", *JOINT_NAMES]) + "\n")
        out.write((str(rows) if t is None else f"{t:.6f}") + ","
                  + ",".join("nan" if math.isnan(v) else f"{v:.4f}" for v in angles) + "\n")
        out.flush()
        rows += 1
    click.echo(f"{rows} samples ({name}" + (f", motion {motion}" if motion else
                                             ", mixed over motions") + ")", err=True)


@glove.command("eval")
@click.option("--kind", type=click.Choice(("dg5", "5dt", "both")), default="dg5",
              show_default=True, help="Glove design(s) to evaluate.")
@click.option("--trials", type=int, default=5, show_default=True,
              help="Calibration trials per motion (>= 3).")
@click.option("--test-trials", type=int, default=3, show_default=True,
              help="Trials per motion in the later sessions.")
@click.option("--seed", type=int, default=0, show_default=True, help="First seed.")
@click.option("--seeds", type=int, default=1, show_default=True,
              help="Independent repetitions (new users, glove, sessions); tables hold means.")
@click.option("--config", "config_name", type=click.Choice(("tuning", "heldout")),
              default="tuning", show_default=True,
              help="Simulator configuration: the spreads the estimators' options were chosen "
                   "on, or other figures for each (larger play, noise, nonlinearity, slip, "
                   "gain and offset spreads; users' rest postures, grasp styles and DIP/PIP "
                   "ratios spread farther).")
@click.option("--json", "json_out", type=click.Path(dir_okay=False),
              help="Write every table as JSON.")
def eval_(kind, trials, test_trials, seed, seeds, config_name, json_out):
    """The seed's tables (per finger, motion, model: MCP error, R^2) on simulated data."""
    from .._io import check_output, write_json
    from ..sensors.glove import GLOVE_HELDOUT, GLOVE_TUNING, EvalOptions, evaluate

    config = GLOVE_HELDOUT if config_name == "heldout" else GLOVE_TUNING

    if json_out:
        check_output(json_out, what="JSON file")  # before the evaluation, not after it
    kinds = ("dg5", "5dt") if kind == "both" else (kind,)
    results = {}
    for k in kinds:
        results[k] = evaluate(EvalOptions(kind=k, trials=trials, test_trials=test_trials,
                                          seed=seed, seeds=seeds, config=config))
    for k, res in results.items():
        _print_eval(k, res)
    if json_out:
        write_json(json_out, {"kinds": list(kinds), "results": results})  # NaN -> null
        click.echo(f"wrote {json_out}")


def _print_eval(kind: str, res: dict) -> None:
    click.echo(f"== {kind} ({res['config']['simulator']['label']} simulator configuration): "
               "mean joint-3 (MCP) error, deg, against the simulated truth; "
               "'const' is the constant answer (mean calibration posture) on the same samples")
    loto = res["conditions"]["loto"]["representative"]
    fingers = ("thumb", "index", "middle", "ring", "little")
    click.echo("leave one trial out, motion known (seed Tables 2-5, 'Ave.' row):")
    click.echo(f"{'variant':<16}" + "".join(f"{f:>8}" for f in fingers) + f"{'const':>8}")
    for v, rows in loto["tables"].items():
        ave = rows["Ave."]
        click.echo(f"{v:<16}" + "".join(f"{ave[f]['mcp_error_deg']:8.2f}" for f in fingers)
                   + f"{loto['summary'][v]['baseline_mcp_error_deg']:8.2f}")
    click.echo("all samples, per condition: rewear = same user, glove put on again; user2 = "
               "another user; both after an open/fist range calibration, except user2-raw; "
               "rep = calibrated motions, other = motions not calibrated")
    short = {"loto": "loto", "new_session": "rewear", "second_user": "user2",
             "second_user_raw": "user2-raw", "representative": "rep", "other": "other"}
    head = f"{'variant':<16}"
    cols = []
    for cond, sets in res["conditions"].items():
        for set_name in sets:
            cols.append((cond, set_name))
            head += f"{short.get(cond, cond) + '/' + short.get(set_name, set_name):>18}"
    click.echo(head)
    variants = list(res["conditions"]["new_session"]["representative"]["summary"])
    for v in variants:
        line = f"{v:<16}"
        for cond, set_name in cols:
            s = res["conditions"][cond][set_name]["summary"].get(v)
            line += f"{'-':>18}" if s is None else \
                f"{s['mcp_error_deg']:>9.2f} ({s['baseline_mcp_error_deg']:5.1f})"
        click.echo(line)
