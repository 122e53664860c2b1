"""2D lattices planned as one layer of a prism: the 2D generator with a z axis added.

A 2D map is planned in the plane z = 0 of the prism lattice ``diag(G2, h)``: the prism cell
of a 2D cell is ``V2 x [-h/2, h/2]``, so every distance between a point or a square of the
plane and a cell of the plane equals the 2D distance, and a segment in the plane touches
exactly the prism cells of the 2D cells it touches. Moves stay in the plane (offsets with
k = 0), so ``full`` gives 8 moves on the square lattice and 6 on the hexagonal one.
"""

from __future__ import annotations

import numpy as np

from planner.lattice.lattice import Lattice

__all__ = ["PlanarPrism", "planar_prism"]


class PlanarPrism(Lattice):
    """A 3D prism over a 2D lattice whose neighbours stay in the plane (module docstring).

    Attributes
    ----------
    base : Lattice
        The 2D lattice.
    """

    base: Lattice

    def neighbors(self, kind: str = "face") -> np.ndarray:
        offs = super().neighbors(kind)
        return offs[offs[:, 2] == 0]

    @property
    def cell_area(self) -> float:
        """Area of the 2D cell (m^2)."""
        return self.base.cell_volume

    def __eq__(self, other: object) -> bool:
        return type(other) is PlanarPrism and super().__eq__(other)

    def __hash__(self) -> int:
        return hash(("planar", super().__hash__()))


def planar_prism(base: Lattice) -> PlanarPrism:
    """The prism of a 2D lattice, height = twice its packing radius (cells about as tall
    as wide; the height does not change any 2D result)."""
    g = np.zeros((3, 3))
    g[:2, :2] = base.generator
    g[2, 2] = 2 * base.packing_radius
    p = PlanarPrism(g, name=base.name)
    p.base = base
    return p
