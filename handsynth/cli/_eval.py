"""``handsynth eval``: the paper's accuracy experiment, or the protocol that cannot flatter."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from .._checks import check_path_names
from ..db import MAX_LEARNING_HANDS
from ..errors import InvalidInputError
from ._main import cli, option_names


def _parse_size(text: str, option: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise InvalidInputError(
            f"{option} must be WIDTHxHEIGHT in pixels, e.g. 720x480, got {text!r}") from None
    return w, h


def _parse_list(text: str, option: str) -> tuple[str, ...]:
    items = tuple(t.strip() for t in text.split(",") if t.strip())
    if not items:
        raise InvalidInputError(f"{option} must name at least one item, got {text!r}")
    return items


#: Options of the paper's experiment that the protocol does not take.
_EXPERIMENT_ONLY = ("out_dir", "prefix", "json_frames", "hand", "count", "db_pose_set",
                    "ratio_margin", "mount", "frame_size", "render_size", "workers", "ties",
                    "photo_mm_per_px")
#: The option each library argument or field of this command's errors comes from.
_OPTION_NAMES = {
    **{f"EvalOptions.{field}": option for field, option in (
        ("db_folder", "--db"), ("n_hands", "--hands"), ("frames_per_hand", "--frames"),
        ("pose_sets", "--pose-sets"), ("seed", "--seed"), ("ratio_margin", "--ratio-margin"),
        ("hand", "--hand"), ("conditions", "--conditions"), ("count", "--count"),
        ("db_pose_set", "--db-pose-set"), ("render_size", "--render-size"), ("mount", "--mount"),
        ("frame_size", "--frame-size"), ("workers", "--workers"), ("ties", "--ties"),
        ("photo_mm_per_px", "--photo-mm-per-px"))},
    **{f"ProtocolOptions.{field}": f"--{field.replace('_', '-')}"
       for field in ("frames", "pose_sets", "seed", "rest", "slip")},
    "LearningSetOptions.hands": "--learned-hands",
    "LearningSetOptions.hand_spread": "--hand-spread",
    "methods": "--conditions",          # protocol_methods
    "n": "--hands", "spread": "--hand-spread",  # model_test_hands
    "breadth_follows_scale": "--breadth-follows-scale",
    "scale": "--mesh-scale",            # mesh_test_hands
    "workers": "--workers",             # build_databases
}

#: What ``--protocol`` compares unless ``--conditions`` says otherwise.
PROTOCOL_DEFAULT = "standard,calibrated,fingers,fingers_mean,mlp,ensemble"


@cli.command("eval")
@click.option("--db", "db_folder", type=click.Path(file_okay=False), required=True,
              help="Database folder; the databases needed are built there when missing "
                   "(--protocol: also the learnt estimators).")
@click.option("--protocol", is_flag=True,
              help="The evaluation that cannot flatter (docs/camera_estimator.md): relaxed "
                   "rest postures from an independent generator, --hands model "
                   "hands beyond the four ratios and the glTF hands, the constant open-hand "
                   f"answer beside every figure. --conditions default: {PROTOCOL_DEFAULT}.")
@click.option("--mesh", default="godot_xr_tools,mrtk", show_default=True,
              help="--protocol: glTF hands to test, comma-separated ('' for none): shipped "
                   "ones by name (also webxr_generic), or .gltf/.glb files of hands rigged "
                   "with OpenXR, WebXR, Mixamo, Unity/VRM or MANO joint names, in metres "
                   "(named by their file's stem).")
@click.option("--mesh-scale", type=float, default=1.0, show_default=True, metavar="F",
              help="--protocol: the glTF hands made larger or smaller about the wrist by this "
                   "factor (0.5-2), for a hand of another size than the file's.")
@click.option("--learned-hands", type=int, default=None, metavar="N",
              help="--protocol: random hands of the learnt estimators' learning set "
                   "[default: 4,000 x 100 frames; the ensemble's perceptrons learn from "
                   "four times as many].")
@click.option("--hand-spread", type=float, default=1.5, show_default=True,
              help="--protocol: variation of the model hands' geometry (the learning set's is 1).")
@click.option("--breadth-follows-scale", type=float, default=0.0, show_default=True, metavar="K",
              help="--protocol: the model hands' breadths take their common length scale to "
                   "the power K (1: a hand uniformly smaller or larger, as a child's; 0: "
                   "breadths independent of the lengths, as the learning hands').")
@click.option("--rest", type=click.Choice(["relaxed", "open"]), default="relaxed",
              show_default=True,
              help="--protocol: the test hands' rest postures: relaxed (flexion growing toward "
                   "the little finger) or open (every finger joint flexed 3-5 deg).")
@click.option("--slip", type=float, default=0.0, show_default=True, metavar="K",
              help="--protocol: after the rest frame the device moves on the wrist by a normal "
                   "draw of K times the learning set's mount s.d.s (height 10 mm, shifts 6 and "
                   "8 mm, tilt and roll 4 deg), as a strap slips after calibration.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False), default=None,
              help="Folder for the plots (eval_*.png); none written if not given.")
@click.option("--prefix", default=None,
              help="File-name prefix of the plots [default: eval_, or eval_mesh_ for --hand mesh].")
@click.option("--json", "json_path", type=click.Path(dir_okay=False), default=None,
              help="Write the per-joint figures (and hands, databases, targets) as JSON.")
@click.option("--json-frames", is_flag=True, help="Also put every frame's truth and estimates "
              "into the JSON file (large).")
@click.option("--hands", "n_hands", type=int, default=8, show_default=True,
              help="Test hands with random off-grid ratios.")
@click.option("--frames", "frames", type=int, default=100, show_default=True,
              help="Test frames per hand and per pose set.")
@click.option("--pose-sets", default="paper,natural", show_default=True,
              help="Pose sets of the test frames, comma-separated.")
@click.option("--hand", type=click.Choice(["model", "mesh"]), default="model", show_default=True,
              help="Test hands: MuJoCo model hands, or the realistic glTF mesh hand.")
@click.option("--conditions", default=None,
              help="Databases (or, with --protocol, methods) to compare, comma-separated "
                   "[default: standard,selected,selected_none,personal,calibrated,own_shape].")
@click.option("--count", type=int, default=20448, show_default=True,
              help="Entries per database.")
@click.option("--db-pose-set", type=click.Choice(["paper", "natural"]), default="paper",
              show_default=True, help="Pose set the databases are built from.")
@click.option("--seed", type=int, default=0, show_default=True,
              help="Seed of the test hands and poses.")
@click.option("--ratio-margin", type=float, default=0.5, show_default=True,
              help="How far (in grid steps) the random ratios may lie beyond the grid.")
@click.option("--mount", type=click.Choice(["paper", "whole-hand"]), default="paper",
              show_default=True, help="Camera mount of databases and test frames.")
@click.option("--frame-size", default="720x480", show_default=True,
              help="WIDTHxHEIGHT of the test frames (the live camera's).")
@click.option("--render-size", default=None,
              help="WIDTHxHEIGHT of database renders [default: the library's].")
@click.option("--workers", type=int, default=1, show_default=True,
              help="Worker processes for building missing databases.")
@click.option("--ties", type=click.Choice(["mean", "first"]), default="mean", show_default=True,
              help="Pose reported when several entries match equally well: their mean, or "
                   "the first entry's.")
@click.option("--photo-mm-per-px", type=float, default=0.25, show_default=True,
              help="Scale of the photos that measure model hands for the personal condition.")
@click.option("--quiet", "-q", is_flag=True, help="No progress lines.")
@click.pass_context
@option_names(_OPTION_NAMES)
def eval_(ctx, db_folder, protocol, mesh, mesh_scale, learned_hands, hand_spread,
          breadth_follows_scale, rest, slip, out_dir, prefix,
          json_path, json_frames, n_hands, frames, pose_sets, hand, conditions, count,
          db_pose_set, seed, ratio_margin, mount, frame_size, render_size, workers, ties,
          photo_mm_per_px, quiet) -> None:
    """Accuracy on synthetic ground truth: standard vs selected database.

    Test hands of random off-grid shape are rendered in known poses at the
    camera's resolution and looked up in the standard database, in the
    database chosen by formulas (1)-(4) from their measurements and in a
    database built for the shape measured on a photo of the hand.  Prints
    mean +- s.d. (MAE) of the signed error per joint and the targets.

    With --protocol: the camera estimators (lookups and learnt estimators)
    under relaxed rest postures and hands beyond the four ratios; prints
    the finger flexion MAE beside the constant open-hand answer and the
    skill per hand kind, pose set and method; --json writes every figure
    (per hand, per joint).
    """
    from .._io import check_output, check_outputs, make_folder, write_json
    from ..errors import OutputError
    from ..eval import EvalOptions, evaluate

    check_path_names((("--db", db_folder), ("--out", out_dir)), kind="folder")
    check_path_names([("--json", json_path)])
    if prefix is not None and ("/" in prefix or "\\" in prefix or prefix in (".", "..")):
        raise InvalidInputError(f"--prefix must be the start of a file name (no folder), got {prefix!r}")
    if json_path:  # before the work, not after it
        path = check_output(json_path, what="JSON report",
                            inputs=sorted(Path(db_folder).glob("*.h5")) if db_folder else ())
        if db_folder and path.suffix.lower() in (".h5", ".hdf5") \
                and path.resolve().parent == Path(db_folder).resolve():
            raise OutputError(f"the JSON report {json_path!r} would be a database file in "
                              f"--db {db_folder!r}, which this run reads or builds: choose "
                              "another name")
    say = None if quiet else (lambda line: click.echo(line, err=True))
    if protocol:
        given = [f"--{n.replace('_', '-')}" for n in _EXPERIMENT_ONLY
                 if ctx.get_parameter_source(n) == click.core.ParameterSource.COMMANDLINE]
        if given:
            raise InvalidInputError(f"{', '.join(given)} appl{'ies' if len(given) == 1 else 'y'} "
                                    "to the paper's experiment, not to --protocol")
        _protocol(db_folder, mesh, mesh_scale, learned_hands, hand_spread, json_path, n_hands, frames,
                  _parse_list(pose_sets, "--pose-sets"),
                  _parse_list(PROTOCOL_DEFAULT if conditions is None else conditions, "--conditions"),
                  seed, rest, slip, say, breadth_follows_scale=breadth_follows_scale)
        return
    for n in ("mesh", "mesh_scale", "learned_hands", "hand_spread", "breadth_follows_scale", "rest",
              "slip"):
        if ctx.get_parameter_source(n) == click.core.ParameterSource.COMMANDLINE:
            raise InvalidInputError(f"--{n.replace('_', '-')} applies with --protocol only")
    if conditions is None:
        conditions = "standard,selected,selected_none,personal,calibrated,own_shape"
    if prefix is None:
        prefix = "eval_mesh_" if hand == "mesh" else "eval_"

    options = EvalOptions(
        db_folder=db_folder, n_hands=n_hands, frames_per_hand=frames,
        pose_sets=_parse_list(pose_sets, "--pose-sets"), seed=seed, ratio_margin=ratio_margin,
        hand=hand, conditions=_parse_list(conditions, "--conditions"), count=count,
        db_pose_set=db_pose_set,
        render_size=None if render_size is None else _parse_size(render_size, "--render-size"),
        mount=mount, frame_size=_parse_size(frame_size, "--frame-size"), workers=workers,
        ties=ties, photo_mm_per_px=photo_mm_per_px)
    if out_dir:  # the plot folder and names, before the work, not after it
        plots = make_folder(out_dir, what="--out folder", writable=True)
        check_outputs([("--out", plots / f"{prefix}{name}.png")
                       for name in ("error_hist", "error_vs_distance", "joint_mae")],
                      inputs=[json_path])
    make_folder(db_folder, what="--db folder")  # before the work: a file in the way fails now
    report = evaluate(options, progress=say)
    click.echo(report.format())
    if json_path:
        # not report.write_json: non-finite numbers must become null, not NaN tokens
        path = write_json(json_path, report.to_dict(frames=json_frames), what="JSON report")
        click.echo(f"json: {path}")
    if out_dir:
        for path in report.write_plots(out_dir, prefix=prefix):
            click.echo(f"plot: {path}")
    sys.stdout.flush()


def _protocol(folder, mesh, mesh_scale, learned_hands, hand_spread, json_path, n_hands, frames, pose_sets,
              methods, seed, rest, slip, say, *, breadth_follows_scale=0.0) -> None:
    import time

    from .. import __version__
    from .._io import make_folder, write_json
    from ..db import LearningSetOptions, learning_workers
    from ..estimate import LEARNED_ENSEMBLES, largest_learning_set
    from ..eval import (
        ProtocolOptions,
        describe_methods,
        format_headline,
        mesh_test_hands,
        model_test_hands,
        protocol_headline,
        protocol_methods,
        run_protocol,
    )
    from ..render import CameraMount

    if n_hands < 0:
        raise InvalidInputError(f"--hands must be a non-negative integer, got {n_hands}")
    if learned_hands is not None and not 1 <= learned_hands <= MAX_LEARNING_HANDS:
        raise InvalidInputError(f"--learned-hands must be an integer in [1, {MAX_LEARNING_HANDS:,}], "
                                f"got {learned_hands}")
    if not hand_spread > 0:
        raise InvalidInputError(f"--hand-spread must be a positive number, got {hand_spread}")
    options = ProtocolOptions(frames=frames, pose_sets=pose_sets, seed=seed, rest=rest, slip=slip)
    mount = CameraMount.paper()
    meshes = [m.strip() for m in mesh.split(",") if m.strip()]
    hands = model_test_hands(n_hands, seed=seed + 1, mount=mount, spread=hand_spread,
                             breadth_follows_scale=breadth_follows_scale)
    hands += mesh_test_hands(meshes, mount=mount, scale=mesh_scale) if meshes else []
    if not hands:
        raise InvalidInputError("no test hands: give --hands N > 0 or --mesh NAMES")
    names = [h.name for h in hands]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:  # before the learning, not after it
        raise InvalidInputError(f"two test hands named {', '.join(map(repr, twice))}: --mesh files are "
                                "named by their stem, model hands model0, model1, ...; rename the file")
    data = (LearningSetOptions() if learned_hands is None
            else LearningSetOptions(hands=learned_hands))
    make_folder(folder, what="--db folder")  # before the learning: a file in the way fails now
    # a learning set the folder lacks is rendered on every core (the same set, sooner)
    largest = max(largest_learning_set(data, LEARNED_ENSEMBLES.get(name, ())) for name in methods)
    factories = protocol_methods(methods, folder, data=data, mount=mount, progress=say,
                                 workers=learning_workers(largest))
    t0 = time.perf_counter()
    result = run_protocol(factories, hands, options, progress=say)
    result["seconds"] = round(time.perf_counter() - t0, 1)
    result["headline"] = protocol_headline(result)
    result["methods"] = describe_methods(methods, data=data)
    result["handsynth"] = __version__
    click.echo(format_headline(result["headline"]))
    if json_path:
        path = write_json(json_path, result, what="JSON report", indent=1)
        click.echo(f"json: {path}")
    sys.stdout.flush()
