"""read_shape / read_image on files written by imageio in every format it writes."""

import warnings

import imageio.v3 as iio
import numpy as np
import pytest

from centrality_vision.exceptions import InputError
from centrality_vision.io import read_image, read_shape


def _several_frames():
    return pytest.warns(UserWarning, match=r"frames \(pages\); the first is read")


DARK_ON_WHITE = np.full((12, 14), 255, dtype=np.uint8)
DARK_ON_WHITE[3:8, 4:11] = 10
SHAPE = DARK_ON_WHITE < 128


@pytest.mark.parametrize("suffix", [".png", ".bmp", ".gif", ".tif", ".tiff", ".jpg", ".pgm", ".webp"])
def test_every_format_imageio_writes(tmp_path, suffix):
    path = tmp_path / f"shape{suffix}"
    iio.imwrite(path, DARK_ON_WHITE)
    assert np.array_equal(read_shape(path), SHAPE)  # JPEG's ringing stays far from the mid-grey threshold


def test_single_and_multi_frame_gif_and_colour(tmp_path):
    frames = np.stack([DARK_ON_WHITE, 255 - DARK_ON_WHITE])
    iio.imwrite(tmp_path / "two.gif", frames)
    with _several_frames():
        assert np.array_equal(read_shape(tmp_path / "two.gif"), SHAPE)  # the first frame
    rgb = np.repeat(DARK_ON_WHITE[:, :, None], 3, axis=2)
    iio.imwrite(tmp_path / "rgb.png", rgb)
    assert np.array_equal(read_shape(tmp_path / "rgb.png"), SHAPE)


@pytest.mark.parametrize("colour", [False, True])
def test_multi_page_tiff_gives_its_first_page(tmp_path, colour):
    # tifffile reads the pages as one (pages, rows, cols) series: it was refused as 3D
    tifffile = pytest.importorskip("tifffile")
    pages = np.stack([DARK_ON_WHITE, 255 - DARK_ON_WHITE, DARK_ON_WHITE])
    if colour:
        pages = np.repeat(pages[..., None], 3, axis=3)
    tifffile.imwrite(tmp_path / "pages.tif", pages, photometric="rgb" if colour else "minisblack")
    with tifffile.TiffFile(tmp_path / "pages.tif") as tif:
        assert len(tif.pages) == 3
    with _several_frames():
        assert np.array_equal(read_shape(tmp_path / "pages.tif"), SHAPE)


@pytest.mark.parametrize("compression", ["tiff_lzw", "jpeg", "packbits"])
def test_a_compressed_tiff_is_read_with_or_without_imagecodecs(tmp_path, compression):
    # tifffile needs the optional imagecodecs for LZW (the commonest TIFF compression) and
    # JPEG: such files were "not a readable TIF image"
    from PIL import Image

    pixels = np.where(SHAPE, 0, 255).astype(np.uint8)
    pages = [Image.fromarray(pixels), Image.fromarray(255 - pixels)]
    pages[0].save(tmp_path / "c.tif", compression=compression, save_all=True, append_images=pages[1:])
    with _several_frames():
        read = read_image(tmp_path / "c.tif")
    assert read.shape == SHAPE.shape
    if compression == "jpeg":  # lossy
        with _several_frames():
            assert np.array_equal(read_shape(tmp_path / "c.tif"), SHAPE)
    else:
        np.testing.assert_array_equal(read, pixels)


def test_a_planar_colour_tiff_is_one_colour_image(tmp_path):
    # its samples come first, (3, rows, cols): the first "page" of that array is its red plane
    tifffile = pytest.importorskip("tifffile")
    rgb = np.stack([DARK_ON_WHITE, np.full_like(DARK_ON_WHITE, 30), 255 - DARK_ON_WHITE])
    tifffile.imwrite(tmp_path / "planar.tif", rgb, photometric="rgb", planarconfig="separate")
    np.testing.assert_allclose(read_image(tmp_path / "planar.tif"), rgb.astype(float).mean(axis=0))


def test_a_volume_tiff_page_is_refused_not_read_as_colour(tmp_path):
    tifffile = pytest.importorskip("tifffile")
    volume = np.zeros((3, 16, 16), dtype=np.uint8)
    tifffile.imwrite(tmp_path / "volume.tif", volume, photometric="minisblack", volumetric=True, tile=(16, 16))
    expected = r"volume\.tif: must be a 2D grey or colour image; got a TIFF page of axes ZYX"
    with pytest.raises(InputError, match=expected):
        read_image(tmp_path / "volume.tif")


@pytest.mark.parametrize("width", [2, 3, 4])
def test_a_multi_page_tiff_of_narrow_pages_gives_its_first_page(tmp_path, width):
    # the pages were read as one (pages, rows) image whose "channels" were each page's
    # columns, averaged: a (3, 10) picture for three 10 x 3 pages
    tifffile = pytest.importorskip("tifffile")
    pages = np.arange(3 * 10 * width, dtype=np.uint8).reshape(3, 10, width)
    tifffile.imwrite(tmp_path / "narrow.tif", pages, photometric="minisblack")
    with tifffile.TiffFile(tmp_path / "narrow.tif") as tif:
        assert len(tif.pages) == 3
    with _several_frames():
        np.testing.assert_array_equal(read_image(tmp_path / "narrow.tif"), pages[0])
    # a stack of stacks: its first page too
    tifffile.imwrite(tmp_path / "deep.tif", np.arange(2 * 2 * 6 * 5, dtype=np.uint8).reshape(2, 2, 6, 5))
    with _several_frames():
        np.testing.assert_array_equal(read_image(tmp_path / "deep.tif"), np.arange(30).reshape(6, 5))


def test_a_silhouette_stored_as_transparency(tmp_path):
    rgba = np.zeros((12, 14, 4), dtype=np.uint8)  # black everywhere, opaque on the shape only
    rgba[..., 3] = np.where(SHAPE, 255, 0)
    iio.imwrite(tmp_path / "alpha.png", rgba)
    assert np.array_equal(read_shape(tmp_path / "alpha.png"), SHAPE)


def test_foreground_and_threshold(tmp_path):
    iio.imwrite(tmp_path / "a.png", DARK_ON_WHITE)
    iio.imwrite(tmp_path / "b.png", 255 - DARK_ON_WHITE)
    assert np.array_equal(read_shape(tmp_path / "b.png"), SHAPE)  # white on black: auto finds it too
    grey = DARK_ON_WHITE.copy()
    grey[0, 0] = 100
    iio.imwrite(tmp_path / "c.png", grey)
    assert read_shape(tmp_path / "c.png", threshold=50, foreground="dark").sum() == SHAPE.sum()
    assert read_shape(tmp_path / "c.png", threshold=150, foreground="dark").sum() == SHAPE.sum() + 1
    assert read_image(tmp_path / "c.png")[0, 0] == 100.0


@pytest.mark.parametrize(
    ("name", "content", "match"),
    [
        ("bad.png", b"GIF89a not a png", "not a readable PNG image"),
        # a text file: the decoder's words were "Could not find a backend to open <_io.BytesIO ...>"
        ("text.png", b"hello, world\n", r"not a readable PNG image \(it does not start as a PNG file: b'hello, w'\)"),
        ("text.jpg", b"hello", r"not a readable JPG image \(it does not start as a JPG file"),
        ("bad.png", b"\x89PNG\r\n\x1a\n broken", "not a readable PNG image"),
        ("bad.tif", b"II*\x00 broken", "not a readable TIF image"),
        ("bad.png", b"", "empty"),
        ("none.png", None, "no such file"),
        ("p.txt", b"0 0\n", r"an image must be a \.png, \.bmp"),
    ],
)
def test_bad_files_name_the_file(tmp_path, name, content, match):
    path = tmp_path / name
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(InputError, match=match) as info:
        read_shape(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_uniform_image_and_bad_options(tmp_path):
    iio.imwrite(tmp_path / "u.png", np.full((4, 4), 7, dtype=np.uint8))
    with pytest.raises(InputError, match="uniform"):
        read_shape(tmp_path / "u.png")
    iio.imwrite(tmp_path / "a.png", DARK_ON_WHITE)
    # the threshold is named, with the bound it must respect (the message blamed the image)
    with pytest.raises(InputError, match=r"a.png: `threshold` 0 leaves no dark pixel .* at least 10, its smallest"):
        read_shape(tmp_path / "a.png", threshold=0, foreground="dark")
    with pytest.raises(InputError, match=r"`threshold` 255 leaves no light pixel .* below 255, its largest value"):
        read_shape(tmp_path / "a.png", threshold=255, foreground="light")
    with pytest.raises(InputError, match="`foreground` must be"):
        read_shape(tmp_path / "a.png", foreground="black")
    with pytest.raises(ValueError, match="`threshold` must be a finite real number"):  # a value, not a type
        read_shape(tmp_path / "a.png", threshold=float("nan"))
    with pytest.raises(TypeError, match="`threshold` must be a finite real number"):
        read_shape(tmp_path / "a.png", threshold="half")


def test_an_inverted_looking_shape_warns(tmp_path):
    pixels = DARK_ON_WHITE.copy()
    pixels[5, :5] = 10  # the dark shape reaches the border
    iio.imwrite(tmp_path / "a.png", pixels)
    with pytest.warns(UserWarning, match="looks inverted"):
        mask = read_shape(tmp_path / "a.png", foreground="light")  # the white background taken as the shape
    assert np.array_equal(mask, pixels > 128)


def test_a_0_1_image_is_a_mask(tmp_path):
    iio.imwrite(tmp_path / "m.png", SHAPE.astype(np.uint8))
    assert np.array_equal(read_shape(tmp_path / "m.png"), SHAPE)


@pytest.mark.parametrize("suffix", [".png", ".bmp", ".tif"])
def test_a_1_bit_black_on_white_file_is_the_black_shape(tmp_path, suffix):
    # PIL writes a bool array as a 1-bit image and imageio decodes it as 0/1 again; white
    # (1) is the background here, so reading it as a mask (1 = shape) inverted the shape
    from PIL import Image

    Image.fromarray(~SHAPE).save(tmp_path / f"bw{suffix}")
    with Image.open(tmp_path / f"bw{suffix}") as written:
        assert written.mode == "1"
    assert np.array_equal(read_shape(tmp_path / f"bw{suffix}"), SHAPE)
    assert np.array_equal(read_shape(tmp_path / f"bw{suffix}", foreground="dark"), SHAPE)
    with pytest.warns(UserWarning, match="looks inverted"):
        assert np.array_equal(read_shape(tmp_path / f"bw{suffix}", foreground="light"), ~SHAPE)


def test_a_colour_image_near_float64s_limit_and_a_uniform_image(tmp_path):
    # found by a fuzz run: the channel mean overflowed (then "holds NaN or inf" for a
    # finite image), and an all-black file blamed a `threshold` 0.5 never given
    import tifffile

    pixels = np.full((6, 6, 3), 1.5e308)
    pixels[2:4, 2:4] = 0.0
    tifffile.imwrite(tmp_path / "big.tif", pixels, photometric="rgb")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        grey = read_image(tmp_path / "big.tif")
    np.testing.assert_array_equal(grey, pixels[..., 0])
    iio.imwrite(tmp_path / "black.png", np.zeros((10, 10), np.uint8))
    with pytest.raises(InputError, match=r"black\.png: the image is uniform \(every pixel is 0\)"):
        read_shape(tmp_path / "black.png")


def test_a_complex_tiff_is_refused_not_cut_to_its_real_part(tmp_path):
    # found by a fuzz run: the imaginary part was dropped with only numpy's warning
    import tifffile

    pixels = np.zeros((6, 6), np.complex128)
    pixels[2:4, 2:4] = 1 + 2j
    tifffile.imwrite(tmp_path / "complex.tif", pixels)
    with pytest.raises(InputError, match=r"complex\.tif: the image has complex pixels \(complex128\)"):
        read_image(tmp_path / "complex.tif")


def test_an_image_under_another_formats_suffix_still_reads(tmp_path):
    """Only a file that fails to decode is called not of its suffix's format."""
    pixels = np.arange(64, dtype=np.uint8).reshape(8, 8) * 4
    (tmp_path / "png-named.jpg").write_bytes(iio.imwrite("<bytes>", pixels, extension=".png"))
    np.testing.assert_array_equal(read_image(tmp_path / "png-named.jpg"), pixels)


@pytest.mark.parametrize("suffix", [".tif", ".gif"])
def test_a_file_of_several_frames_is_read_as_its_first_with_a_warning(tmp_path, suffix):
    """A 3-page TIFF or a 3-frame GIF gave its first frame without a word (audit 26); the
    reader now says how many frames it held."""
    frames = np.zeros((3, 20, 24), dtype=np.uint8)
    frames[0, 5:15, 6:18] = 255
    frames[1, 2:8, 2:8] = 255
    frames[2, 10:18, 10:22] = 255
    path = tmp_path / f"stack{suffix}"
    if suffix == ".gif":
        iio.imwrite(path, frames, loop=0)
    else:
        pytest.importorskip("tifffile").imwrite(path, frames, photometric="minisblack")
    with pytest.warns(UserWarning, match=r"holds 3 frames \(pages\); the first is read"):
        image = read_image(path)
    np.testing.assert_array_equal(image > 127, frames[0] > 127)
    iio.imwrite(tmp_path / f"one{suffix}", frames[0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        read_image(tmp_path / f"one{suffix}")
