"""The coset quantizer: every named lattice as the nearest of one or two box roundings."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from planner.lattice import NAMED_LATTICES, Lattice
from planner.lattice.cosets import coset_quantizer, quantize
from planner.match import MultiResVoxelList, _kernels
from planner.match.matcher import _Scorer


@pytest.mark.parametrize("name", NAMED_LATTICES)
def test_cosets_give_the_exact_quantizers_cells_on_every_named_lattice(name):
    rng = np.random.default_rng(1)
    x = rng.uniform(-4, 4, (50000, 3))
    for volume in (0.001, 0.3):
        for lat in (Lattice.named(name, volume), Lattice(Lattice.named(name, volume)
                                                         .generator * 4)):
            cq = coset_quantizer(lat)
            assert cq is not None and cq.cosets <= 2
            assert np.array_equal(quantize(lat, x), lat.quantize(x))


def test_a_lattice_without_a_box_sublattice_falls_back_to_the_generic_quantizer():
    lat = Lattice(np.array([[1.0, 0.31, 0.17], [0.0, 0.93, 0.41], [0.0, 0.0, 1.07]]))
    assert coset_quantizer(lat) is None
    x = np.random.default_rng(2).normal(size=(1000, 3))
    assert np.array_equal(quantize(lat, x), lat.quantize(x))


@pytest.mark.parametrize("name", ["bcc", "mcc"])
def test_the_match_score_is_the_generic_kernels_score(name):
    rng = np.random.default_rng(3)
    ref = rng.uniform(-3, 3, (20000, 3))
    mr = MultiResVoxelList(ref, Lattice.named(name, 0.001), 2)
    pts = ref[:5000] + rng.normal(scale=0.05, size=(5000, 3))
    rots = np.repeat(np.eye(3)[None], 8, axis=0)
    rots[4:] = Rotation.from_rotvec(rng.normal(scale=0.05, size=(4, 3))).as_matrix()
    trans = rng.normal(scale=0.05, size=(8, 3))
    for k in range(2):
        lv = mr.level(k)
        fast = _Scorer(pts, np.ones(len(pts)), lv)(rots, trans)
        generic = np.empty(8)
        _kernels.score_poses(pts, np.ones(len(pts)), rots, trans, *lv.tables, lv.table,
                             lv.bits, generic)
        assert np.array_equal(fast, generic) and fast.max() > 1000
