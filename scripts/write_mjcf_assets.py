"""Write the standard hands and their scenes to assets/hand_mjcf/ (Menagerie layout).

The files are generated from :func:`handsynth.models.hand_mjcf`; a test checks
that the committed files equal the generator's output.  Run after changing
the hand model: ``python scripts/write_mjcf_assets.py``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from handsynth._io import write_text
from handsynth.render import standard_assets

OUT = Path(__file__).resolve().parents[1] / "assets" / "hand_mjcf"

if __name__ == "__main__":
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                            formatter_class=argparse.RawDescriptionHelpFormatter).parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    for name, text in standard_assets().items():
        write_text(OUT / name, text, what="MJCF asset")
        print(f"wrote {OUT / name}")
