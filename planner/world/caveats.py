"""What a person must know before trusting a path planned in a world, said wherever the
path is reported (the printed result, ``--json``, path files)."""

from __future__ import annotations

__all__ = ["NO_ORIGIN", "world_warnings"]

#: what :func:`world_warnings` says of a cloud without a sensor origin
NO_ORIGIN = ("no sensor origin: space the sensor never saw counts as free, so this path may "
             "cross unseen obstacles (a wall above a lidar's field of view); give --origin "
             "x,y,z for a single scan, a pose list (--format poses) for several")


def world_warnings(world) -> list[str]:
    """One line per caveat of ``world`` (a :class:`planner.World`): today, a plain cloud
    whose unseen space counts as free (:data:`NO_ORIGIN`)."""
    obst = getattr(world, "obstacles", None)
    if (world is None or world.unknown_policy != "free" or obst is None
            or obst.has_free_space):
        return []
    if not len(obst.points):  # a voxel map (.3dmap) says what every voxel is: no sensor
        return []
    return [NO_ORIGIN]
