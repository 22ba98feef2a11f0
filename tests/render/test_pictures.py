"""Pictures written to files and labelled."""

import cv2
import numpy as np
import pytest

from handsynth.errors import InvalidInputError
from handsynth.render import label_image, read_image, write_png


def test_rgb_and_rgba_pictures_keep_their_colours(tmp_path):
    rgba = np.zeros((6, 8, 4), np.uint8)
    rgba[..., 0] = 255  # opaque red...
    rgba[..., 3] = 255
    rgba[:3, :, 3] = 100  # ...translucent in the top half
    write_png(tmp_path / "rgba.png", rgba)
    back = cv2.imread(str(tmp_path / "rgba.png"), cv2.IMREAD_UNCHANGED)  # BGRA
    np.testing.assert_array_equal(back[..., [2, 1, 0, 3]], rgba)
    write_png(tmp_path / "rgb.png", rgba[..., :3])
    np.testing.assert_array_equal(cv2.imread(str(tmp_path / "rgb.png"))[..., ::-1], rgba[..., :3])
    grey = np.arange(48, dtype=np.uint8).reshape(6, 8)
    write_png(tmp_path / "grey.png", grey)
    np.testing.assert_array_equal(cv2.imread(str(tmp_path / "grey.png"), cv2.IMREAD_UNCHANGED),
                                  grey)


@pytest.mark.parametrize("img", [np.zeros((6, 8, 2), np.uint8), np.zeros((6, 8, 5), np.uint8),
                                 np.zeros((6, 8), np.float32), np.zeros((0, 8, 3), np.uint8),
                                 np.zeros((2, 6, 8, 3), np.uint8)])
def test_pictures_png_cannot_hold_are_refused_by_name(tmp_path, img):
    with pytest.raises(InvalidInputError, match=r"rgb .*got dtype .* shape"):
        write_png(tmp_path / "x.png", img)
    assert not (tmp_path / "x.png").exists()


def test_label_image_leaves_its_input_alone():
    img = np.full((40, 120, 3), 30, np.uint8)
    before = img.copy()
    out = label_image(img, "label")
    np.testing.assert_array_equal(img, before)
    assert out is not img and not np.shares_memory(out, img)
    assert out.shape == img.shape and out.dtype == np.uint8
    assert (out != img).any()


@pytest.mark.parametrize("img, word", [([[0, 1]], "img"), (np.zeros((40, 120, 3)), "img"),
                                       (np.zeros((40, 120, 4), np.uint8), "img")])
def test_label_image_refuses_what_is_not_a_picture(img, word):
    with pytest.raises(InvalidInputError, match=word):
        label_image(img, "x")


def test_read_image_reads_what_write_png_wrote(tmp_path):
    rgb = np.random.default_rng(0).integers(0, 256, (6, 8, 3), dtype=np.uint8)
    write_png(tmp_path / "rgb.png", rgb)
    np.testing.assert_array_equal(read_image(tmp_path / "rgb.png"), rgb[..., ::-1])  # BGR
    rgba = np.concatenate([rgb, np.full((6, 8, 1), 7, np.uint8)], axis=2)
    write_png(tmp_path / "rgba.png", rgba)
    np.testing.assert_array_equal(read_image(str(tmp_path / "rgba.png")), rgb[..., ::-1])
    deep = (rgb[..., 0].astype(np.uint16) << 8) | 0xFF
    assert cv2.imwrite(str(tmp_path / "deep.png"), deep)
    np.testing.assert_array_equal(read_image(tmp_path / "deep.png"), rgb[..., 0])
    with pytest.raises(InvalidInputError, match=r"cannot read the frame .*nothing\.png"):
        read_image(tmp_path / "nothing.png", what="frame")


@pytest.mark.parametrize("name", ["x.jpg", "x.PNG.bak", "x", "x.png.tmp"])
def test_write_png_refuses_a_name_that_is_not_a_png(tmp_path, name):
    # issue: write_png("x.jpg", img) wrote PNG bytes under a .jpg name
    with pytest.raises(InvalidInputError, match=rf"path must name a \.png file .*got "
                                                rf"'{tmp_path / name}'"):
        write_png(tmp_path / name, np.zeros((4, 4), np.uint8))
    assert not (tmp_path / name).exists()
    assert write_png(str(tmp_path / "upper.PNG"), np.zeros((4, 4), np.uint8)).is_file()


@pytest.mark.parametrize("path, words", [(None, "got None"), (3, "got int 3"), ("", "got ''")])
def test_read_image_and_write_png_refuse_a_path_that_is_not_a_name(path, words):
    # issue: read_image(None) gave a raw pathlib TypeError
    for call in (lambda: read_image(path), lambda: write_png(path, np.zeros((4, 4), np.uint8))):
        with pytest.raises(InvalidInputError, match=rf"path must .*{words}"):
            call()
