"""Notebook helpers of mavac.experiments.kabir_setups: Fig. 7 diagnosis and the reach-test setup."""

import dataclasses
import math

import numpy as np

from mavac.experiments import kabir_setups as K
from mavac.params import SamplingParams, SetupSpaceParams
from mavac.setups.sampling import uniform_setups

SPACE = SetupSpaceParams(res_x=0.5, res_y=0.5, res_alpha=math.radians(120))
SAMPLING = dataclasses.replace(SamplingParams(), gd_step_x=0.5, gd_step_y=0.5, gd_step_alpha=math.radians(120))


def toy_baseline():
    """Patch 0 is reached only at x = 0, with patch 1; x = 0.5 reaches 1-5, x = 1 reaches 1-9:
    the absolute round always walks away from patch 0."""
    setups = uniform_setups(SPACE)
    cover = np.zeros((len(setups), 10), dtype=bool)
    for j, (x, _, _) in enumerate(setups):
        cover[j, {0.0: [0, 1], 0.5: [1, 2, 3, 4, 5], 1.0: list(range(1, 10))}[round(x, 1)]] = True
    return K.Baseline("toy", setups, cover, np.ones(10), np.ones(10, dtype=int), 0)


def test_absolute_round_walks_away_from_a_rare_patch_and_exhausts_the_grid():
    b = toy_baseline()
    ca = K.exhaustion_diagnosis(b, SPACE, SAMPLING, variant="CA_XY", seed=0)
    assert not ca["covers_target"] and ca["n_rfc"] == len(b.setups)  # every grid setup drawn
    assert ca["missing_patches"] == 1 and ca["grid_setups_reaching_min"] == 12
    assert ca["seeds_reaching_missing"] == 12
    assert ca["kept_after_conservative"] == 12 and ca["kept_after_absolute"] == 0
    c = K.exhaustion_diagnosis(b, SPACE, SAMPLING, variant="C_XY", seed=0)
    assert c["covers_target"] and c["missing_patches"] == 0 and c["kept_after_absolute"] is None


def test_contrast_setup_reaches_about_half_of_the_stain():
    b = toy_baseline()
    j = np.flatnonzero(np.all(b.setups == K.contrast_setup(b), axis=1))[0]
    assert b.cover[j].sum() == 5  # x = 0.5: half of the ten coverable patches
