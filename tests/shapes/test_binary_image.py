"""as_binary_image: masks, grey images, the automatic side and the inverted-mask warning."""

import warnings

import numpy as np
import pytest

from centrality_vision._validation import as_binary_image


def _disk(n=20, r=6, value_in=1, value_out=0, dtype=np.uint8):
    yy, xx = np.mgrid[:n, :n]
    inside = (yy - n / 2) ** 2 + (xx - n / 2) ** 2 < r**2
    return np.where(inside, value_in, value_out).astype(dtype), inside


@pytest.mark.parametrize(
    ("value_in", "value_out", "dtype"),
    [
        (0, 255, np.uint8),
        (255, 0, np.uint8),
        (0, 65535, np.uint16),
        (0.1, 0.9, np.float32),
        (True, False, bool),
        (1, 0, np.int64),
    ],
)
def test_auto_finds_the_shape_on_either_background(value_in, value_out, dtype):
    image, inside = _disk(value_in=value_in, value_out=value_out, dtype=dtype)
    np.testing.assert_array_equal(as_binary_image(image), inside)


def test_explicit_sides_and_threshold():
    image, inside = _disk(value_in=0, value_out=255)
    np.testing.assert_array_equal(as_binary_image(image, foreground="dark"), inside)
    np.testing.assert_array_equal(as_binary_image(image, foreground="light"), ~inside)
    grey = image.astype(float)
    grey[0, 0] = 100.0  # below a threshold of 150, above one of 50
    assert as_binary_image(grey, foreground="dark", threshold=150)[0, 0]
    assert not as_binary_image(grey, foreground="dark", threshold=50)[0, 0]


def test_default_threshold_is_half_the_range_of_the_values():
    image = np.full((10, 10), 200.0)
    image[3:6, 3:6] = 100.0
    image[4, 4] = 149.0  # below (100 + 200) / 2: dark, part of the shape
    image[3, 3] = 151.0  # above: light, background
    mask = as_binary_image(image)
    assert mask[4, 4] and not mask[3, 3] and mask.sum() == 8


def test_masks_keep_true_as_shape_and_dark_inverts_them():
    mask = np.zeros((10, 10), bool)
    mask[:, :7] = True  # touches most of the border: still the mask's meaning
    np.testing.assert_array_equal(as_binary_image(mask), mask)
    np.testing.assert_array_equal(as_binary_image(mask.astype(np.uint8), foreground="dark"), ~mask)


def test_inverted_mask_warns_only_when_asked():
    inside = np.zeros((20, 20), bool)
    inside[4:16, 0:8] = True  # a shape touching the left border: its inverse touches most of it
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        as_binary_image(inside, check_inverted=True)
        as_binary_image(~inside)  # not asked
    with pytest.warns(UserWarning, match="looks inverted"):
        as_binary_image(~inside, check_inverted=True)


def test_input_not_modified_and_not_returned():
    image, _ = _disk(dtype=bool)
    before = image.copy()
    out = as_binary_image(image)
    out[:] = False
    np.testing.assert_array_equal(image, before)


@pytest.mark.parametrize(
    ("image", "kwargs", "error", "match"),
    [
        (np.full((4, 4), 7.0), {}, ValueError, "uniform"),
        (np.zeros((4, 4), bool), {}, ValueError, "at least one foreground"),
        (np.ones((4, 4)), {"foreground": "bright"}, ValueError, "`foreground` must be one of"),
        (np.ones((4, 4)), {"threshold": "half"}, TypeError, "`threshold` must be a finite real"),
        (np.ones((4, 4)), {"threshold": np.nan}, ValueError, "`threshold` must be a finite real"),
        (np.ones((2, 2, 3)), {}, ValueError, "2D array"),
        (np.array([[1 + 1j, 0]]), {}, TypeError, "real numbers"),
        (np.array([["a"]]), {}, TypeError, "`image` must hold real numbers"),
    ],
)
def test_bad_inputs_name_the_parameter(image, kwargs, error, match):
    with pytest.raises(error, match=match):
        as_binary_image(image, **kwargs)


def test_a_background_taken_as_the_shape_warns_even_when_it_covers_the_whole_border():
    # the usual inverted mask: a centred shape's background touches every border pixel
    inside = np.zeros((20, 20), bool)
    inside[5:15, 6:12] = True
    with pytest.warns(UserWarning, match="looks inverted: its shape .* touches 76 of the 76"):
        as_binary_image(~inside, check_inverted=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        as_binary_image(np.ones((20, 20), bool), check_inverted=True)  # no background: nothing to judge
