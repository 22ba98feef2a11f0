from pathlib import Path

import mujoco

from handsynth.render import standard_assets

ASSETS = Path(__file__).resolve().parents[2] / "assets" / "hand_mjcf"


def test_committed_assets_match_the_generator():
    for name, text in standard_assets().items():
        assert (ASSETS / name).read_text() == text, f"{name} is stale: run scripts/write_mjcf_assets.py"


def test_scenes_load_from_files():
    for side in ("right", "left"):
        m = mujoco.MjModel.from_xml_path(str(ASSETS / f"scene_{side}.xml"))
        assert m.ncam == 3 and m.nq == 20 and m.nkey == 6
