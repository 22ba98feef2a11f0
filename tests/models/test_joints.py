import numpy as np
import pytest

from handsynth import JOINT_NAMES
from handsynth.errors import InvalidPoseError
from handsynth.models import JOINT_LIMITS_DEG, as_angles, joint_index


def test_canonical_names_and_order():
    assert JOINT_NAMES[:4] == ("thumb_cmc_flex", "thumb_cmc_abd", "thumb_mcp_flex", "thumb_ip_flex")
    expected = [f"{f}_{j}" for f in ("index", "middle", "ring", "little")
                for j in ("mcp_flex", "mcp_abd", "pip_flex", "dip_flex")]
    assert list(JOINT_NAMES[4:]) == expected
    assert len(set(JOINT_NAMES)) == 20


def test_limits_are_published_ranges():
    lim = dict(zip(JOINT_NAMES, JOINT_LIMITS_DEG))
    assert JOINT_LIMITS_DEG.shape == (20, 2)
    assert np.all(JOINT_LIMITS_DEG[:, 0] < JOINT_LIMITS_DEG[:, 1])
    # AAOS: MCP flexion to 90, PIP to 100, DIP to 90; abduction symmetric
    for f in ("index", "middle", "ring", "little"):
        assert lim[f"{f}_mcp_flex"][1] == 90
        assert lim[f"{f}_pip_flex"][1] == 100
        assert lim[f"{f}_dip_flex"][1] == 90
        assert lim[f"{f}_mcp_abd"][0] == -lim[f"{f}_mcp_abd"][1]
    assert not JOINT_LIMITS_DEG.flags.writeable


def test_as_angles_accepts_mapping_and_fills_zero():
    a = as_angles({"index_pip_flex": 30})
    assert a[joint_index("index_pip_flex")] == 30 and a.sum() == 30


@pytest.mark.parametrize(
    "bad, words",
    [
        ({"index_pip": 10}, ["index_pip"]),
        ({"index_pip_flex": float("nan")}, ["index_pip_flex", "nan"]),
        ({"index_pip_flex": 150}, ["index_pip_flex", "150", "limits"]),
        (np.zeros(19), ["shape", "(19,)"]),
        ({"thumb_ip_flex": "x"}, ["thumb_ip_flex", "'x'"]),
    ],
)
def test_bad_angles_name_the_problem(bad, words):
    with pytest.raises(InvalidPoseError) as exc:
        as_angles(bad)
    for w in words:
        assert w in str(exc.value)


def test_row_of_bad_batch_is_named():
    a = np.zeros((5, 20))
    a[3, 6] = np.inf
    with pytest.raises(InvalidPoseError, match="index_pip_flex.*row 3"):
        as_angles(a)
