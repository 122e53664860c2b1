"""A saved world is trusted for what its cells are, not for its digest: edited and
re-digested worlds are refused whenever their source map is there to rebuild them from.

The digest catches damage; someone who read the format can recompute it (it is no
signature). ``--check-source`` (and, by default, any load whose unchanged source map is
found) rebuilds the cells from the source with the file's own settings and compares them.
"""

from __future__ import annotations

import io
import zlib

import numpy as np
import pytest

from planner.cli import main
from planner.errors import MapError
from planner.world.check import digest
from planner.world.file import load_world
from planner.world.trust import verify_world

QUERY = ["--start", "1,1,1", "--goal", "7.6,7.8,0.8"]


def tampered(src, *, clear=False, one=False, radius=None, policy=None) -> bytes:
    """The saved world ``src`` edited as someone who read the format would: every cell or
    one cell freed, radius or policy changed, and the digest recomputed to match."""
    with np.load(src) as z:
        d = {k: z[k] for k in z.files}
    if clear or one:
        bits = np.frombuffer(zlib.decompress(d["blocked"].tobytes()), np.uint8).copy()
        if clear:
            bits[:] = 0
        else:
            i = np.flatnonzero(bits)[len(np.flatnonzero(bits)) // 2]
            bits[i] &= bits[i] - 1  # its lowest blocked cell freed
        d["blocked"] = np.frombuffer(zlib.compress(bits), np.uint8)
    if radius is not None:
        d["radius"] = np.array(float(radius))
    if policy is not None:
        d["unknown_policy"] = np.array(policy)
    d["digest"] = np.array(digest(d))
    buf = io.BytesIO()
    np.savez(buf, **d)
    return buf.getvalue()


@pytest.fixture(scope="module")
def office_world(tmp_path_factory):
    out = tmp_path_factory.mktemp("trust") / "office.npz"
    assert main(["world", "office", "--radius", "0.2", "--out", str(out)]) == 0
    return out


EDITS = {"obstacles cleared": {"clear": True}, "radius 0.2 -> 1.5": {"radius": 1.5},
         "radius 0.2 -> 0": {"radius": 0.0}, "one cell freed": {"one": True}}


@pytest.mark.parametrize("edit", sorted(EDITS))
@pytest.mark.parametrize("flag", [[], ["--check-source"]])
def test_an_edited_and_redigested_world_is_refused(office_world, tmp_path, edit, flag,
                                                   capsys):
    w = tmp_path / "edited.npz"
    w.write_bytes(tampered(office_world, **EDITS[edit]))
    load_world(w)  # well formed: the digest alone cannot tell
    assert main(["plan", str(w), *QUERY, *flag]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "edited.npz" in err[0], err
    assert "cells differ from those its source map office.ply gives" in err[0]
    assert main(["compare", str(w), *QUERY, *flag]) == 2
    capsys.readouterr()


def test_the_honest_world_passes_and_trust_world_skips_the_check(office_world, tmp_path,
                                                                capsys):
    assert main(["plan", str(office_world), *QUERY, "--check-source"]) == 0
    assert verify_world(load_world(office_world), required=True)
    w = tmp_path / "edited.npz"
    w.write_bytes(tampered(office_world, clear=True))
    # asked for: the digest alone decides (README: catches damage, not edits)
    assert main(["plan", str(w), *QUERY, "--trust-world"]) == 0
    capsys.readouterr()
    with pytest.raises(MapError, match="blocked cells differ"):
        verify_world(load_world(w), required=False)


def test_a_world_whose_source_is_absent_is_checked_only_when_asked(tmp_path, capsys):
    cloud = tmp_path / "cloud.xyz"
    cloud.write_text("".join(f"{x} {y} 0.5\n" for x in range(4) for y in range(4)))
    w = tmp_path / "w.npz"
    assert main(["world", str(cloud), "--radius", "0.3", "--cell-volume", "0.05", "--out",
                 str(w)]) == 0
    (tmp_path / "edited.npz").write_bytes(tampered(w, radius=1.0))
    assert main(["plan", str(tmp_path / "edited.npz"), "--start", "0.5,0.5,2", "--goal",
                 "2.5,2.5,2"]) == 2  # the source is beside it: checked by default
    capsys.readouterr()
    cloud.unlink()
    assert not verify_world(load_world(tmp_path / "edited.npz"), required=False)
    assert main(["plan", str(tmp_path / "edited.npz"), "--start", "0.5,0.5,2", "--goal",
                 "2.5,2.5,2", "--check-source"]) == 2
    assert "cloud.xyz not found" in capsys.readouterr().err
