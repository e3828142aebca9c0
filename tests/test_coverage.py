"""Coverage C and overlap O (MAVAC eq. 1-2) on hand-made visibility matrices."""

import numpy as np
import pytest

from mavac.inspection.coverage import cover_counts, coverage_overlap, mean_pairwise_overlap


def test_hand_made():
    v = np.array([[1, 1, 0, 0, 0],
                  [0, 1, 1, 0, 0],
                  [0, 1, 0, 0, 0]], dtype=bool)
    assert cover_counts(v).tolist() == [1, 3, 1, 0, 0]
    C, O = coverage_overlap(v)
    assert C == pytest.approx(3 / 5)
    assert O == pytest.approx(1 / 5)


def test_matches_set_definitions():
    rng = np.random.default_rng(0)
    v = rng.random((7, 30)) < 0.2
    cover = [set(np.flatnonzero(r)) for r in v]
    Cg = set().union(*cover)
    Og = set()
    for i in range(len(cover)):
        for j in range(i + 1, len(cover)):
            Og |= cover[i] & cover[j]
    assert coverage_overlap(v) == pytest.approx((len(Cg) / 30, len(Og) / 30))


def test_no_pose_and_one_pose():
    assert coverage_overlap(np.zeros((0, 4), bool)) == (0.0, 0.0)
    assert coverage_overlap(np.array([1, 0, 1, 1], bool)) == (0.75, 0.0)


def test_denominator_is_S():
    v = np.array([[1, 1]], dtype=bool)
    assert coverage_overlap(v, n_elements=4) == (0.5, 0.0)


def test_bad_input():
    with pytest.raises(ValueError, match="visible"):
        coverage_overlap(np.zeros((1, 2, 3), bool))
    with pytest.raises(ValueError, match="n_elements"):
        coverage_overlap(np.zeros((0, 0), bool))


def test_mean_pairwise_overlap_is_the_mean_over_pairs_of_the_intersections():
    v = np.array([[1, 1, 0, 0, 0],
                  [0, 1, 1, 0, 0],
                  [0, 1, 0, 0, 0]], dtype=bool)
    # pairs (0,1), (0,2), (1,2) share element 1 each: mean 1 element of 5
    assert mean_pairwise_overlap(v) == pytest.approx(1 / 5)
    rng = np.random.default_rng(3)
    for h in (2, 3, 7):
        v = rng.random((h, 40)) < 0.3
        brute = np.mean([np.sum(v[i] & v[j]) / 40 for i in range(h) for j in range(i + 1, h)])
        assert mean_pairwise_overlap(v) == pytest.approx(brute)
        # eq. 2 (covered at least twice) is never below the mean pairwise overlap
        assert coverage_overlap(v)[1] >= mean_pairwise_overlap(v) - 1e-12
    assert mean_pairwise_overlap(np.ones((1, 5), bool)) == 0.0
    assert mean_pairwise_overlap(np.zeros((0, 5), bool)) == 0.0
    with pytest.raises(ValueError, match="n_elements"):
        mean_pairwise_overlap(v, n_elements=0)
