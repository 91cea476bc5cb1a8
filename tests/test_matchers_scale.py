"""Kernel widths relative to the problem's own scale, and image-space pairwise terms."""

import numpy as np
import pytest

from matchers import Problem, get
from matchers.blocks.pairwise import kernel_sigma2, pairwise_affinity
from matchers.core.scale import median_spacing

PAIRWISE = ["sm", "rrwm", "mos"]


def test_median_spacing_pools_both_views_and_skips_duplicates():
    a = np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 0.0]])  # distances 3, 3, 0
    b = np.array([[0.0, 0.0], [0.0, 5.0]])  # 5
    assert median_spacing(a, b) == 3.0
    assert median_spacing(np.zeros((4, 3)), np.zeros((1, 3))) == 1.0  # no positive distance
    assert median_spacing(np.zeros((0, 3)), np.zeros((0, 3))) == 1.0


def scene(seed, n=7, extent=20.0):
    rng = np.random.default_rng(seed)
    p1 = rng.uniform(0, extent, (n, 3))
    perm = rng.permutation(n)
    p2 = (p1 + 0.05 * rng.normal(size=p1.shape))[perm]
    return p1, p2, np.argsort(perm)


@pytest.mark.parametrize("name", PAIRWISE)
def test_relative_width_equals_the_absolute_one_when_the_scales_coincide(name):
    p1, p2, _ = scene(0)
    problem = Problem(p1, p2)
    spacing = median_spacing(p1, p2)
    relative = get(name)(problem, sigma_scale=0.1)
    absolute = get(name)(problem, sigma2=(0.1 * spacing) ** 2)
    np.testing.assert_array_equal(relative.scores, absolute.scores)
    np.testing.assert_array_equal(relative.pairs, absolute.pairs)


@pytest.mark.parametrize("name", PAIRWISE)
def test_defaults_are_todays_absolute_sigma2(name):
    p1, p2, _ = scene(1)
    problem = Problem(p1, p2)
    np.testing.assert_array_equal(get(name)(problem).scores, get(name)(problem, sigma2=0.5).scores)
    assert kernel_sigma2(problem) == 0.5


@pytest.mark.parametrize("name", PAIRWISE)
def test_relative_width_is_invariant_to_the_unit_of_length(name):
    p1, p2, _ = scene(2)
    metres = get(name)(Problem(p1, p2), sigma_scale=0.05)
    millimetres = get(name)(Problem(p1 * 1000, p2 * 1000), sigma_scale=0.05)
    np.testing.assert_allclose(metres.scores, millimetres.scores, atol=1e-9)


def test_image_space_edge_lengths_come_from_the_pixels():
    p1, p2, _ = scene(3)
    rng = np.random.default_rng(3)
    px1, px2 = rng.uniform(0, 1000, (7, 2)), rng.uniform(0, 1000, (7, 2))
    problem = Problem(p1, p2, pixels1=px1, pixels2=px2)
    np.testing.assert_array_equal(
        pairwise_affinity(problem, 50.0, pairwise="image"),
        pairwise_affinity(Problem(px1, px2), 50.0),
    )
    assert kernel_sigma2(problem, sigma_scale=0.1, pairwise="image") == pytest.approx(
        (0.1 * median_spacing(px1, px2)) ** 2
    )


@pytest.mark.parametrize("name", PAIRWISE)
def test_image_space_matching_follows_the_pixels_not_the_3d_positions(name):
    """Pixels carry the correspondence (a similar image layout), the 3-D positions do not."""
    rng = np.random.default_rng(4)
    n = 7
    px1 = rng.uniform(0, 1000, (n, 2))
    perm = rng.permutation(n)
    px2 = (px1 + rng.normal(size=px1.shape))[perm]
    truth = np.argsort(perm)
    p1, p2 = rng.uniform(0, 20, (n, 3)), rng.uniform(0, 20, (n, 3))
    problem = Problem(p1, p2, pixels1=px1, pixels2=px2)
    image = get(name)(problem, pairwise="image", sigma_scale=0.05)
    assert np.array_equal(image.pairs[:, 1], truth[image.pairs[:, 0]])
    positions = get(name)(problem, sigma_scale=0.05)
    assert not np.array_equal(positions.pairs[:, 1], truth[positions.pairs[:, 0]])


@pytest.mark.parametrize("name", PAIRWISE)
def test_image_space_without_pixels_or_with_a_fixed_affinity_is_an_error(name):
    p1, p2, _ = scene(5)
    with pytest.raises(ValueError, match="pixels1"):
        get(name)(Problem(p1, p2), pairwise="image")
    with pytest.raises(ValueError, match="pairwise"):
        get(name)(Problem(p1, p2), pairwise="camera")
    with pytest.raises(ValueError, match="sigma2/sigma_scale"):
        get(name)(Problem(p1, p2), sigma2=0.5, sigma_scale=0.1)
    with pytest.raises(ValueError, match="sigma_scale"):
        get(name)(Problem(p1, p2), sigma_scale=-1.0)
    with pytest.raises(ValueError, match="affinity"):
        get(name)(Problem(p1, p2), affinity=np.zeros((49, 49)), sigma_scale=0.1)
