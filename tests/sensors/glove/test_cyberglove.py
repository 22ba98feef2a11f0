import numpy as np
import pytest

from handsynth.errors import RecordingError
from handsynth.models import JOINT_NAMES, natural_pose_set
from handsynth.sensors.glove import CYBERGLOVE_COLUMNS, GloveWarning, fit_synergies, read_cyberglove_csv


def _export(angles: np.ndarray, rng) -> np.ndarray:
    """22 glove columns from canonical angles (the inverse of the reader's mapping)."""
    a = {n: angles[:, i] for i, n in enumerate(JOINT_NAMES)}
    mid = a["middle_mcp_abd"]
    cols = {
        "thumb_rotation": a["thumb_cmc_flex"], "thumb_mcp": a["thumb_mcp_flex"],
        "thumb_ip": a["thumb_ip_flex"], "thumb_abduction": a["thumb_cmc_abd"],
        "middle_index_abduction": a["index_mcp_abd"] - mid,
        "ring_middle_abduction": mid - a["ring_mcp_abd"],
        "little_ring_abduction": a["ring_mcp_abd"] - a["little_mcp_abd"],
        "palm_arch": rng.uniform(0, 20, len(angles)),
        "wrist_flexion": rng.uniform(-40, 40, len(angles)),
        "wrist_abduction": rng.uniform(-10, 10, len(angles)),
    }
    for f in ("index", "middle", "ring", "little"):
        for j in ("mcp", "pip", "dip"):
            cols[f"{f}_{j}"] = a[f"{f}_{j}_flex"]
    return np.column_stack([cols[c] for c in CYBERGLOVE_COLUMNS])


@pytest.fixture
def poses():
    p = natural_pose_set(300, seed=5)
    p[:, JOINT_NAMES.index("middle_mcp_abd")] = 0.0   # the glove cannot see it
    return p


def test_header_file_round_trip_in_radians(tmp_path, poses):
    rng = np.random.default_rng(0)
    data = np.radians(_export(poses, rng))
    order = rng.permutation(len(CYBERGLOVE_COLUMNS))           # any column order
    names = ["time_s"] + [CYBERGLOVE_COLUMNS[i] for i in order]
    lines = [",".join(names)] + [",".join([f"{k / 100:.2f}"] + [f"{v:.9f}" for v in row[order]])
                                 for k, row in enumerate(data)]
    p = tmp_path / "glove.csv"
    p.write_text("\n".join(lines) + "\n")
    got = read_cyberglove_csv(p, units="rad")
    np.testing.assert_allclose(got, poses, atol=1e-6)


def test_semicolon_export_with_decimal_commas(tmp_path, poses):
    """A 22-sensor export saved by a spreadsheet that writes decimal commas."""
    data = _export(poses, np.random.default_rng(2))
    lines = [";".join(CYBERGLOVE_COLUMNS)]
    lines += [";".join(f"{v:.6f}".replace(".", ",") for v in row) for row in data]
    p = tmp_path / "glove.csv"
    p.write_bytes(("\ufeff" + "\r\n".join(lines) + "\r\n").encode("utf-8"))
    np.testing.assert_allclose(read_cyberglove_csv(p), poses, atol=1e-5)


def test_headerless_file_in_default_order_and_synergies(tmp_path, poses):
    data = _export(poses, np.random.default_rng(1))
    p = tmp_path / "glove.csv"
    np.savetxt(p, data, delimiter=",", fmt="%.5f")
    got = read_cyberglove_csv(p)
    np.testing.assert_allclose(got, poses, atol=1e-4)
    syn = fit_synergies(got, k=2, source=str(p))
    assert syn.explained.sum() > 0.5 and syn.source.endswith("glove.csv")


def test_nan_rows_stay_nan(tmp_path, poses):
    data = _export(poses[:5], np.random.default_rng(2))
    lines = [",".join(CYBERGLOVE_COLUMNS)] + [",".join(f"{v:.3f}" for v in r) for r in data]
    lines[3] = lines[3].replace(lines[3].split(",")[5], "", 1)
    p = tmp_path / "g.csv"
    p.write_text("\n".join(lines) + "\n")
    with pytest.warns(GloveWarning, match=r"g.csv: 1 of 5 rows have an empty or NaN cell "
                                          r"\(at line 4\)"):
        got = read_cyberglove_csv(p)
    assert np.isnan(got[2]).all() and np.isfinite(got[[0, 1, 3, 4]]).all()


def test_bad_files_are_named(tmp_path, poses):
    p = tmp_path / "g.csv"
    p.write_text("thumb_mcp,index_pip\n1,2\n")
    with pytest.raises(RecordingError, match="missing column.*thumb_rotation"):
        read_cyberglove_csv(p)
    data = _export(poses[:3], np.random.default_rng(3))
    lines = [",".join(CYBERGLOVE_COLUMNS)] + [",".join(f"{v:.3f}" for v in r) for r in data]
    lines[2] = "oops," + lines[2].split(",", 1)[1]
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=r"g.csv, line 3: thumb_rotation is 'oops'"):
        read_cyberglove_csv(p)
    np.savetxt(p, _export(poses, np.random.default_rng(4)), delimiter=",")
    with pytest.raises(RecordingError, match=r"degrees\? pass units='deg'"):
        read_cyberglove_csv(p, units="rad")
    np.savetxt(p, np.radians(_export(poses, np.random.default_rng(4))), delimiter=",")
    with pytest.raises(RecordingError, match=r"radians\? pass units='rad'"):
        read_cyberglove_csv(p)
    with pytest.raises(RecordingError, match="no such file"):
        read_cyberglove_csv(tmp_path / "none.csv")


@pytest.mark.parametrize("cell", ["1e308", "inf", "-inf", "1e5"])
def test_a_corrupt_cell_is_refused_by_line(tmp_path, poses, cell):
    # 1e308 crashed the synergy fit with a traceback; inf and 1e5 were taken silently
    data = _export(poses[:20], np.random.default_rng(5))
    lines = [",".join(CYBERGLOVE_COLUMNS)] + [",".join(f"{v:.3f}" for v in r) for r in data]
    lines[4] = cell + "," + lines[4].split(",", 1)[1]
    p = tmp_path / "g.csv"
    p.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=rf"g.csv, line 5: thumb_rotation is '{cell}', "
                                             r"beyond any joint angle"):
        read_cyberglove_csv(p)


def test_synergy_errors_name_their_source(poses):
    from handsynth.errors import EstimationError, InvalidInputError

    with pytest.raises(EstimationError, match=r"^g.csv: 2 finite postures cannot give 2 "):
        fit_synergies(poses[:2], k=2, source="g.csv")
    huge = poses[:30].copy()
    huge[3, 4] = 1e300
    with pytest.raises(InvalidInputError, match=r"^g.csv: index_mcp_flex is 1e\+300 deg"):
        fit_synergies(huge, k=2, source="g.csv")


@pytest.mark.parametrize("spell", [
    lambda c: c.replace("_", " ").title(),          # "Thumb Rotation", "Index Mcp"
    lambda c: c.upper(),                            # "THUMB_ROTATION"
    lambda c: c.replace("little", "pinky"),         # "pinky_mcp"
])
def test_a_header_spelt_otherwise_is_read_by_its_names(tmp_path, poses, spell):
    # each was refused as missing every one of the 19 columns
    data = _export(poses, np.random.default_rng(4))
    lines = [",".join(["Time (s)"] + [spell(c) for c in CYBERGLOVE_COLUMNS])]
    lines += [",".join([f"{k / 100:.2f}"] + [f"{v:.6f}" for v in row]) for k, row in enumerate(data)]
    p = tmp_path / "glove.csv"
    p.write_text("\n".join(lines) + "\n")
    np.testing.assert_allclose(read_cyberglove_csv(p), poses, atol=1e-5)


def test_a_sensor_stuck_in_every_row_is_warned_about(tmp_path, poses):
    # a glove sensor unplugged for the whole export was learnt as a joint that never moves
    data = _export(poses, np.random.default_rng(5))
    data[:, CYBERGLOVE_COLUMNS.index("ring_pip")] = 0.0
    p = tmp_path / "glove.csv"
    p.write_text("\n".join([",".join(CYBERGLOVE_COLUMNS)]
                           + [",".join(f"{v:.6f}" for v in row) for row in data]) + "\n")
    with pytest.warns(GloveWarning, match=r"glove.csv: ring_pip read\(s\) 0 in all 300 complete "
                                          r"rows \(a sensor stuck or unplugged\?\)"):
        read_cyberglove_csv(p)


def test_a_header_of_other_names_is_shown_when_refused(tmp_path, poses):
    data = _export(poses, np.random.default_rng(6))
    names = [f"S{k}" for k in range(len(CYBERGLOVE_COLUMNS))]
    p = tmp_path / "glove.csv"
    p.write_text("\n".join([",".join(names)] + [",".join(f"{v:.6f}" for v in row)
                                                for row in data]) + "\n")
    with pytest.raises(RecordingError, match=r"\(its header: S0, S1, S2, S3, S4, S5, S6, S7, "
                                             r"\.\.\.\)"):
        read_cyberglove_csv(p)
