"""``planner lattices`` (the lattice property table) and ``planner stats`` (the paper's
Table I and Figs. 3-5)."""

from __future__ import annotations

import argparse

from planner.analysis import measure


def lattices(a: argparse.Namespace) -> int:
    """Print the table of lattice properties at ``a.cell_volume`` (m^3)."""
    rows = measure.lattice_table(cell_volume=a.cell_volume, n_points=a.points, seed=a.seed)
    print(f"cell volume {a.cell_volume:g} m^3; distances and radii in metres; "
          f"nsm = normalised second moment; mean_error = eq. (13) on {a.points} "
          "uniform points; points_per_s = quantize() throughput")
    print(measure.format_table(rows, None if a.all_columns else measure.TABLE_COLUMNS))
    return 0


def stats(a: argparse.Namespace) -> int:
    """Reproduce the paper's Table I and Figs. 3-5 into ``a.out``."""
    from planner.analysis.paper import reproduce  # lazy: numba, scipy

    return reproduce(a.out, rotations=a.rotations, volumes=a.volumes, samples=a.samples,
                     seed=a.seed, data=a.data, quick=a.quick, table1_volume=a.table1_volume)
