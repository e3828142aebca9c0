"""Open / enclosed heap labels: a ray straight up from the heap hits the machine or not."""

import numpy as np
import pytest
import trimesh

from mavac.cleaning.regions import ENCLOSED, OPEN, heap_regions, region_counts
from mavac.geometry.machines import (SCENE_NAMES, dust_heaps, load_machine, machine_from_mesh)


def _box(lo, hi):
    return trimesh.creation.box(bounds=np.array([lo, hi], dtype=float))


def _slab_over_plinth():
    """A 0.2 m plinth, and a slab at 0.5-0.6 m on a back wall: the plinth's front half is under
    the slab, its top beyond the slab is open sky."""
    parts = [_box([0, 0, 0], [1, 1, 0.2]),  # plinth
             _box([0, 0.9, 0.2], [1, 1, 0.6]),  # back wall
             _box([0, 0.3, 0.5], [1, 1, 0.6])]  # slab, overhangs y in [0.3, 0.9]
    return machine_from_mesh(trimesh.boolean.union(parts, engine="manifold"))


def test_box_under_a_slab_is_enclosed_and_the_slab_top_is_open():
    machine = _slab_over_plinth()
    heaps = np.array([[0.5, 0.6, 0.2],  # plinth top under the slab
                      [0.5, 0.1, 0.2],  # plinth top in front of the slab
                      [0.5, 0.6, 0.6]])  # slab top
    assert heap_regions(machine, heaps).tolist() == [ENCLOSED, OPEN, OPEN]


def test_box_top_is_open():
    machine = machine_from_mesh(_box([0, 0, 0], [1, 1, 1]))
    assert heap_regions(machine, [[0.5, 0.5, 1.0], [0.0, 0.0, 1.0]]).tolist() == [OPEN, OPEN]


def test_open_top_pocket_floor_is_open():
    pocket = trimesh.boolean.difference([_box([0, 0, 0], [1, 1, 0.5]), _box([0.1, 0.1, 0.2], [0.9, 0.9, 0.6])],
                                        engine="manifold")
    machine = machine_from_mesh(pocket)
    heaps = [[0.5, 0.5, 0.2], [0.15, 0.15, 0.2], [0.05, 0.5, 0.5]]  # floor, floor by a wall, rim
    assert heap_regions(machine, heaps).tolist() == [OPEN, OPEN, OPEN]


def test_closed_enclosure_floor_is_enclosed():
    shell = trimesh.boolean.difference([_box([0, 0, 0], [1, 1, 1]), _box([0.1, 0.1, 0.1], [0.9, 0.9, 0.9])],
                                       engine="manifold")
    assert heap_regions(machine_from_mesh(shell), [[0.5, 0.5, 0.1]]).tolist() == [ENCLOSED]


@pytest.mark.parametrize("name", SCENE_NAMES)
def test_scenes_have_open_and_enclosed_heaps(name):
    """Both scenes have concavities with material above (the bench's overhang and slot, the
    sander's shelf, the milling box) and open tops."""
    machine = load_machine(name)
    regions = heap_regions(machine, dust_heaps(machine, seed=1))
    counts = region_counts(regions)
    assert counts[OPEN] + counts[ENCLOSED] == len(regions)
    assert counts[OPEN] > counts[ENCLOSED] > 10


def test_milling_box_holds_enclosed_heaps():
    """MAVAC: the robot "detected dust inside the box" of the milling machine: our enclosure's
    floor and table carry heaps, all of them under the enclosure's roof."""
    from mavac.geometry.machines import MILL_BODY_SIZE, mill_heights

    machine = load_machine("milling_machine")
    heaps = dust_heaps(machine, seed=1)
    heights = mill_heights()
    inside = (heaps[:, 2] > heights["enclosure_floor"] - 0.01) & (heaps[:, 2] < heights["roof"] - 0.05)
    inside &= np.abs(heaps[:, 0]) < MILL_BODY_SIZE[0] / 2 - 0.01  # within the casing (the mill is centred)
    inside &= np.abs(heaps[:, 1]) < MILL_BODY_SIZE[1] / 2  # not on the bench top in front or behind
    assert inside.sum() >= 10
    assert np.all(heap_regions(machine, heaps[inside]) == ENCLOSED)


def test_heap_regions_handles_no_heaps_and_refuses_bad_input():
    machine = machine_from_mesh(_box([0, 0, 0], [1, 1, 1]))
    assert heap_regions(machine, np.zeros((0, 3))).shape == (0,)
    with pytest.raises(ValueError, match="lift"):
        heap_regions(machine, [[0.5, 0.5, 1.0]], lift=0.0)
    with pytest.raises(ValueError, match="heaps"):
        heap_regions(machine, [[0.5, 0.5]])
    with pytest.raises(TypeError, match="machine"):
        heap_regions(None, [[0.5, 0.5, 1.0]])
