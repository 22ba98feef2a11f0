"""``handsynth demo``: the main job on an embedded default."""

from __future__ import annotations

from pathlib import Path

import click

from ._main import cli


@cli.command()
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("demo_out"), show_default=True, help="Folder for the pictures.")
@click.option("--tile-width", type=click.IntRange(64, 1440), default=360, show_default=True,
              help="Width of one picture in pixels.")
def demo(out_dir: Path, tile_width: int) -> None:
    """Render the open hand, a fist and a pinch for the smallest and largest grid shapes."""
    import time

    from ..models import HandShape
    from ..render import CameraMount, backend, contact_sheet
    from ..render._io import write_png

    t = time.perf_counter()
    grid = HandShape.grid()
    shapes = {"smallest": grid[0], "largest": grid[-1]}
    out_dir.mkdir(parents=True, exist_ok=True)
    for name, mount in (("hands_paper_mount", CameraMount.paper()),
                        ("hands_whole_hand_mount", CameraMount.whole_hand())):
        path = out_dir / f"{name}.png"
        write_png(path, contact_sheet(shapes, mount=mount, tile_width_px=tile_width))
        click.echo(f"wrote {path}")
    click.echo(f"smallest = {grid[0].name}, largest = {grid[-1].name}; "
               f"MUJOCO_GL={backend()}; {time.perf_counter() - t:.1f} s")
