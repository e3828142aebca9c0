import numpy as np
import pytest

from mavac.seeding import MAX_SEED, check_seed, int_seed, rng_for


def test_same_inputs_same_stream():
    assert np.array_equal(rng_for(3, "rrt", 1, 2).random(5), rng_for(3, "rrt", 1, 2).random(5))
    assert int_seed(3, "rrt", 7) == int_seed(3, "rrt", 7)


def test_streams_differ_by_seed_stage_and_index():
    seeds = {int_seed(s, st, i) for s in (0, 1) for st in ("rrt", "ik") for i in (0, 1, 2)}
    assert len(seeds) == 12  # consecutive plans never share an OMPL seed


def test_int_seed_in_range_and_not_zero():
    values = [int_seed(s, "x", i) for s in range(20) for i in range(20)]
    assert min(values) >= 1 and max(values) <= MAX_SEED


@pytest.mark.parametrize("bad", [-1, MAX_SEED + 1])
def test_seed_out_of_range_names_parameter(bad):
    with pytest.raises(ValueError, match="seed"):
        check_seed(bad)
    with pytest.raises(ValueError, match="seed"):
        rng_for(bad, "x")


def test_bad_types():
    with pytest.raises(ValueError, match="seed must be an integer"):
        check_seed(1.5)
    with pytest.raises(TypeError, match="seed"):
        check_seed("1")
    with pytest.raises(TypeError, match="stage"):
        rng_for(1, "")
    with pytest.raises(ValueError, match="index"):
        int_seed(1, "x", -2)
