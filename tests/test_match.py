"""Scan matching on multi-resolution lattice voxel lists, and pose proximity."""

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from planner.cli import main
from planner.errors import LatticeError, MapError
from planner.lattice import NAMED_LATTICES, Lattice
from planner.match import MultiResVoxelList, PoseIndex, match, pose_error, pose_matrix

DATA = Path(__file__).resolve().parents[1] / ".." / "shared" / "data"
VELODYNE = DATA / "velodyne"


def _room(rng, n=30000):
    """Points on the walls, floor and ceiling of a 10 x 6 x 3 m room with two pillars."""
    faces = []
    for _ in range(n // 10):
        u = rng.uniform(0, 1, 3) * [10, 6, 3]
        faces += [[u[0], 0, u[2]], [u[0], 6, u[2]], [0, u[1], u[2]], [10, u[1], u[2]],
                  [u[0], u[1], 0], [u[0], u[1], 3]]
        faces += [[2 + 0.5 * np.cos(a), 2 + 0.5 * np.sin(a), u[2]] for a in
                  rng.uniform(0, 2 * np.pi, 2)]
        faces += [[7, 3 + u[1] / 6, u[2]], [7 + u[0] / 10, 3, u[2]]]
    return np.array(faces) - [5, 3, 1.5]


@pytest.mark.parametrize("lattice", NAMED_LATTICES)
def test_recovers_a_known_transform_on_every_lattice(lattice):
    rng = np.random.default_rng(7)
    ref = _room(rng)
    truth = pose_matrix([0.3, -0.2, 0.1, 2.0, -1.0, 6.0])
    src = (_room(rng) - truth[:3, 3]) @ truth[:3, :3]  # the room seen from the moved pose
    res = match(src, ref, lattice=lattice, cell_volume=0.001, levels=4)
    pos, rot = pose_error(res.transform, truth)
    assert pos < 0.05 and rot < 1.0
    # The discrete search ends at the refinement's plane level (level 1), then refines.
    assert res.levels == 4 and len(res.iterations) == 3 and res.refinement > 0


def test_the_continuous_refinement_beats_the_discrete_pose():
    rng = np.random.default_rng(5)
    ref = _room(rng)
    truth = pose_matrix([0.3, -0.2, 0.1, 2.0, -1.0, 6.0])
    src = (_room(rng) - truth[:3, 3]) @ truth[:3, :3]
    for lattice in ("cubic", "fcc"):
        fine = match(src, ref, lattice=lattice, levels=4)
        coarse = match(src, ref, lattice=lattice, levels=4, refine=False)
        assert len(coarse.iterations) == 4 and coarse.refinement == 0
        e_fine, e_coarse = pose_error(fine.transform, truth), pose_error(coarse.transform, truth)
        assert e_fine[0] < 0.005 and e_fine[1] < 0.05, e_fine  # discrete: 6-26 mm
        assert e_fine[0] < e_coarse[0] / 2 and e_fine[1] < e_coarse[1] / 2, (e_fine, e_coarse)


@pytest.mark.skipif(not VELODYNE.is_dir(), reason="Velodyne pair not present")
def test_velodyne_pair_matches_its_published_relative_pose():
    from planner.io import load_points

    a = load_points(VELODYNE / "251370668.pcd")
    b = load_points(VELODYNE / "251371071.pcd")
    truth = np.loadtxt(VELODYNE / "relative.txt")
    init = pose_matrix([0.3, -0.2, 0.1, 0, 0, 5]) @ truth
    res = match(b, a, lattice="fcc", init=init)
    pos, rot = pose_error(res.transform, truth)
    assert pos < 0.05 and rot < 1.0


def test_cli_match_prints_transform_as_json(tmp_path, capsys):
    rng = np.random.default_rng(3)
    truth = pose_matrix([0.2, 0.1, 0.0, 0, 0, 4])
    np.save(tmp_path / "ref.npy", _room(rng, 20000))
    np.save(tmp_path / "src.npy", (_room(rng, 20000) - truth[:3, 3]) @ truth[:3, :3])
    assert main(["match", str(tmp_path / "src.npy"), str(tmp_path / "ref.npy"),
                 "--lattice", "bcc", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert pose_error(np.array(out["transform"]), truth)[0] < 0.05
    assert out["levels"] == 4 and out["score"] > 0


def test_cli_match_bad_input_is_one_line_exit_2(tmp_path, capsys):
    (tmp_path / "bad.npy").write_bytes(b"not numpy")
    assert main(["match", str(tmp_path / "bad.npy"), str(tmp_path / "bad.npy")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("planner: error:")
    with pytest.raises(SystemExit) as exc:
        main(["match", "a.npy", "b.npy", "--init", "1,2,3"])
    assert exc.value.code == 2


@pytest.mark.parametrize("lattice", NAMED_LATTICES)
def test_score_counts_the_moved_points_in_occupied_cells_by_every_rounding(lattice):
    """``MultiResVoxelList.score`` equals counting ``contains`` of the moved points, with
    the coset rounding, the generic quantizer and (cubic only) the dedicated rounding."""
    rng = np.random.default_rng(3)
    ref = _room(rng, 5000)
    mr = MultiResVoxelList(ref, Lattice.named(lattice, 0.001), 2)
    src = _room(rng, 2000)
    rots = Rotation.from_rotvec(rng.normal(scale=0.05, size=(5, 3))).as_matrix()
    trans = rng.normal(scale=0.05, size=(5, 3))
    roundings = ["auto", "cosets", "generic"] + (["cubic"] if lattice == "cubic" else [])
    for level in (0, 1):
        want = [mr.contains(src @ r.T + t, level).sum() for r, t in zip(rots, trans, strict=True)]
        assert 0 < min(want) < len(src)
        for rounding in roundings:
            got = mr.score(src, rots, trans, level=level, rounding=rounding)
            assert got.tolist() == want, (rounding, level)
    w = rng.uniform(0, 2, len(src))
    got = mr.score(src, rots[:1], trans[:1], weights=w)
    assert np.isclose(got[0], w[mr.contains(src @ rots[0].T + trans[0])].sum())


def test_score_names_a_rounding_the_lattice_lacks():
    mr = MultiResVoxelList(_room(np.random.default_rng(0), 500), Lattice.named("fcc", 0.001))
    with pytest.raises(LatticeError, match="axis-aligned cubic"):
        mr.score(np.zeros((3, 3)), np.eye(3)[None], np.zeros((1, 3)), rounding="cubic")
    with pytest.raises(LatticeError, match="rounding must be"):
        mr.score(np.zeros((3, 3)), np.eye(3)[None], np.zeros((1, 3)), rounding="round")
    with pytest.raises(MapError, match="level must be"):
        mr.score(np.zeros((3, 3)), np.eye(3)[None], np.zeros((1, 3)), level=4)


@pytest.mark.parametrize("lattice", ["cubic", "fcc"])
def test_pose_index_agrees_with_brute_force(lattice):
    rng = np.random.default_rng(11)
    stored = rng.uniform(-20, 20, (2000, 3))
    queries = rng.uniform(-20, 20, (3000, 3))
    idx = PoseIndex(1.0, lattice=lattice)
    idx.add(stored)
    d = np.linalg.norm(queries[:, None] - stored[None], axis=2).min(axis=1)
    assert np.array_equal(idx.near(queries), d <= 1.0)
    q = np.concatenate([stored[:5], Rotation.random(5, random_state=1).as_quat()], axis=1)
    assert idx.near(q).all()  # (N, 7) pose rows: a stored position is near itself


@pytest.mark.parametrize("lattice", ["bcc", "hex"])
def test_pose_index_grown_in_many_adds_agrees_with_brute_force_where_poses_pile_up(lattice):
    rng = np.random.default_rng(12)
    spread = rng.uniform(-20, 20, (1500, 3))
    pile = rng.normal(scale=0.3, size=(3000, 3)) + [2.0, -1.0, 0.5]  # hundreds per cell
    stored = np.concatenate([spread, pile])[rng.permutation(4500)]
    idx = PoseIndex(0.5, lattice=lattice)
    for part in np.array_split(stored, 60):  # the arrays and the hash map grow many times
        idx.add(part)
    assert len(idx) == 4500
    queries = np.concatenate([rng.uniform(-20, 20, (3000, 3)),
                              rng.normal(scale=1.0, size=(3000, 3)) + [2.0, -1.0, 0.5]])
    d = np.sqrt(((queries[:, None] - stored[None]) ** 2).sum(axis=2)).min(axis=1)
    got = idx.near(queries)
    assert np.array_equal(got, d <= 0.5) and 0.2 < got.mean() < 0.8
    assert not PoseIndex(0.5).near(queries[:3]).any()  # an empty index is near nothing
